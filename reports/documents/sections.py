"""The sections of a test event's report as one JSON document for its typst
template: title, event, global figures, a page per shift with its segments, the
image appendix and the methods.  All times are in the test event's time zone."""

import shutil
from datetime import date, datetime, timedelta
from pathlib import Path

from django.conf import settings
from django.utils import timezone
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop, ngettext, pgettext

from common.deferred_text import DeferredText, deferred
from events.selectors.taxonomy import taxonomy_text
from reports import formatting as fmt
from reports.charts import bars
from reports.charts.sketch import track_sketch
from reports.charts.timeline import draw_timeline
from reports.documents import tables
from reports.documents.maps import TrackMaps, tile_source
from reports.documents.options import FULL, STANDARD, ReportOptions
from reports.documents.pictures import Pictures
from reports.documents.typesetting import TEMPLATE_DIR
from reports.documents.wording import report_text, shift_name
from reports.selectors import content
from reports.selectors.formulas import FORMULAS, translated_definitions
from reports.selectors.plans import test_plan
from reports.selectors.provenance import keywords, provenance
from reports.selectors.statistics import (
    CONFIDENCE,
    EventStatistics,
    Figures,
    event_statistics,
    segment_scope,
)
from telemetry.selectors.recordings import recordings_by_master, summary
from telemetry.selectors.tracks import GAP_SECONDS
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

DEFAULT_LOGO = TEMPLATE_DIR / "logo.svg"
FONT_NOTE = gettext_noop(
    "DejaVu Sans with WenQuanYi Micro Hei or Noto CJK for Chinese, Japanese and Korean, "
    "and Noto Color Emoji for emoji"
)
SKETCH_SIZE = (190.0, 135.0)  # points: a segment's map sketch
OVERVIEW_SIZE = (6.5, 4.8)  # inches: a shift's overview map
MAX_GAPS_LISTED = 200


class Sections:
    """Builds the document; chart and picture files go into ``root``."""

    def __init__(self, event, options: ReportOptions, root: Path, progress, time_stage):
        self.event = event
        self.options = options
        self.root = root
        self.progress = progress
        self.time_stage = time_stage
        self.tz = event.tzinfo
        self.mode = LOCAL_TRACK if options.local else GPS_TRACK
        self.warnings: list[str] = []
        self.reasons = content.reasons_by_key(event)
        self.pictures = Pictures(root, options.image_appendix, self.warnings, time_stage)
        tiles = tile_source(event, options, self.mode)
        self.maps = TrackMaps(self.mode, tiles, self.pictures, time_stage)
        self.file_count = 0
        self.appendix: list[dict] = []

    @property
    def tiles_used(self) -> bool:
        return self.maps.tiles_used

    def _file(self, stem: str, suffix: str = ".png") -> Path:
        self.file_count += 1
        return self.root / f"{stem}-{self.file_count}{suffix}"

    def document(self) -> dict:
        event = self.event
        self.progress(0.02, deferred(gettext_noop("statistics")))
        scope = self.options.scope
        # What the report covers, read once: the whole test event, a shift or a leg.
        self.scope_name = content.scope_name(**scope)
        with self.time_stage(gettext_noop("statistics (queries and distances)")):
            stats = event_statistics(event, self.mode, tracks=True, **scope)
        shifts = content.shifts_of(event, self.options.shift)
        self.legs = content.legs_by_shift(shifts, self.options.leg)
        self.notes = content.notes_by_master(event, **scope)
        self.images = content.images_by_segment(event, **scope)
        self.recordings = recordings_by_master(**segment_scope(event, **scope, via="segment__"))
        runs_by_shift = stats.runs_by_shift()
        total_steps = 2 + len(shifts) + len(stats.runs)
        self.step = 0

        def tick(step: DeferredText):
            self.step += 1
            self.progress(0.05 + 0.9 * self.step / total_steps, step)

        tick(deferred(gettext_noop("global statistics")))
        global_section = self._global(stats, shifts)
        shift_sections = []
        for shift in shifts:
            runs = runs_by_shift.get(shift.id, [])
            shift_sections.append(self._shift(shift, stats.by_shift.get(shift.id), runs, tick))
        return {
            "title": self._title(),
            # The plan judges whole cases over the whole test event: a report of a
            # shift or leg has only part of its runs, so it leaves the plan out.
            "test_plan": None
            if self.options.shift
            else tables.test_plan_rows(test_plan(event, self.mode, runs=stats.runs)),
            "provisional": stats.provisional,
            "event": self._event_rows(),
            "mode": _position_mode(self.mode),
            "global": global_section,
            "shifts": shift_sections,
            "level": self.options.level,
            "appendix": self.appendix,
            "methods": self._methods(stats, shifts),
            "text": report_text(),
            "provenance": self._provenance(),
        }

    def _provenance(self) -> dict:
        built = timezone.now()
        stamp = provenance(self.event, self.options.as_dict(), built)
        final = self.event.finalised
        return {
            **stamp,
            "keywords": keywords(stamp),
            # The stamp's UTC form is for --verify (keywords); the reader sees the
            # report's one zone.
            "built": fmt.timestamp(built, self.tz),
            "taxonomy": taxonomy_text(self.event),
            "final": fmt.timestamp(final, self.tz) if final else None,
            "amendments": [
                _("%(when)s: %(record)s %(kind)s by %(who)s")
                % {
                    "when": fmt.timestamp(datetime.fromisoformat(a["at"]), self.tz),
                    "record": a["record"],
                    "kind": a["kind_text"],
                    "who": a["by"] or a["channel"],
                }
                + (f" ({a['reason']})" if a["reason"] else "")
                for a in stamp["amendments"]
            ],
            "amended": ngettext(
                "amended %(count)s time after finalisation",
                "amended %(count)s times after finalisation",
                len(stamp["amendments"]),
            )
            % {"count": len(stamp["amendments"])},
            "options": [[k, str(v)] for k, v in stamp["options"].items()],
        }

    def _title(self) -> dict:
        o = self.options
        site_logo = getattr(settings, "FTT_REPORT_LOGO", "")
        logo = Path(o.logo or site_logo) if (o.logo or site_logo) else DEFAULT_LOGO
        logo_name = None
        if logo.exists():
            logo_name = "logo" + logo.suffix.lower()
            shutil.copy(logo, self.root / logo_name)
        else:
            self.warnings.append(
                _("Logo %(file)s not found; the title page has none.") % {"file": logo}
            )
        name = o.name or _("Field test report: %(event)s") % {"event": self.event}
        if o.shift is not None:
            name = f"{name} · {self.scope_name}"
        return {
            "name": name,
            "version": o.version,
            "recipient": o.recipient,
            "recipient_address": list(o.recipient_address),
            "creator": o.creator,
            "creator_address": list(o.creator_address),
            "date": fmt.day(date.today()),
            "generated": fmt.timestamp(timezone.now(), self.tz),
            "logo": logo_name,
        }

    def _event_rows(self) -> list:
        e = self.event
        return tables.label_rows(
            [
                (_("Test event"), str(e.pk)),
                (_("Report of"), self.scope_name if self.options.shift else _("whole test event")),
                (_("Location"), e.location or fmt.DASH),
                (_("Software version"), e.version or fmt.DASH),
                (_("Start"), fmt.timestamp(e.start, self.tz)),
                (pgettext("time", "End"), fmt.timestamp(e.end, self.tz) if e.end else _("open")),
                (_("Time zone"), e.time_zone),
                (_("Positions"), _position_mode(self.mode)),
                (_("Note"), e.note or fmt.DASH),
            ]
        )

    def _global(self, stats: EventStatistics, shifts) -> dict:
        empty = stats.overall  # same shape, used for shifts without runs
        labels = [shift_name(s.number) for s in shifts]
        per_shift = [stats.by_shift.get(s.id, empty) for s in shifts]
        has = [s.id in stats.by_shift for s in shifts]
        distance_rows = []
        reliability_rows = []
        for shift, f, present in zip(shifts, per_shift, has, strict=True):
            head = [
                shift_name(shift.number),
                shift.vehicle.short_description,
                tables.weather_text(self.legs[shift.id]),
            ]
            if not present:
                distance_rows.append(head + [fmt.DASH] * 6)
                reliability_rows.append(head[:1] + [fmt.DASH] * 7)
                continue
            distance_rows.append(head + tables.distance_cells(f))
            reliability_rows.append(tables.reliability_row(head[0], f))
        o = stats.overall
        distance_rows.append([self.scope_name, "", ""] + tables.distance_cells(o))
        reliability_rows.append(tables.reliability_row(self.scope_name, o))
        vehicles = {s.vehicle_id: s.vehicle for s in shifts}
        vehicle_rows = [
            tables.reliability_row(vehicles[vid].short_description, f)
            for vid, f in stats.by_vehicle.items()
        ]
        reason_rows = []
        for key in sorted(
            set(o.manual_seconds_by_reason) | set(o.interventions_by_reason),
            key=lambda k: self.reasons[k].shown_short if k in self.reasons else k,
        ):
            reason = self.reasons.get(key)
            reason_rows.append(
                [
                    reason.shown_short if reason else key,
                    _("yes") if key in stats.counted_reasons else _("no"),
                    str(o.interventions_by_reason.get(key, 0)),
                    fmt.duration(o.manual_seconds_by_reason.get(key, 0.0)),
                ]
            )
        present = [(lab, f) for lab, f, p in zip(labels, per_shift, has, strict=True) if p]
        with self.time_stage(gettext_noop("figures: charts")):
            charts_out = self._charts(present)
        return {
            "summary": tables.figure_rows(o),
            "distance_rows": distance_rows,
            "reliability_rows": reliability_rows,
            "vehicle_rows": vehicle_rows,
            "reason_rows": reason_rows,
            "charts": charts_out,
        }

    def _charts(self, present: list[tuple[str, Figures]]) -> list[str | None]:
        if not present:
            return []
        names = [label for label, _ in present]
        made = (
            bars.distance_chart(
                names,
                [f.auto_distance for _, f in present],
                [f.manual_distance for _, f in present],
                str(self._file("distance", ".svg")),
            ),
            bars.reasons_chart(
                names,
                [f.interventions_by_reason for _, f in present],
                self.reasons,
                str(self._file("reasons", ".svg")),
            ),
        ) + tuple(
            bars.estimate_chart(
                names,
                [getattr(f, key) for _, f in present],
                str(self._file(key, ".svg")),
                key.upper(),
                unit,
                scale=scale,
            )
            for key, unit, scale in (("mdbi", "m", 1.0), ("mtbi", "h", 3600.0))
        )
        return [_name(path) for path in made]

    def _timeline(self, shift, runs) -> str | None:
        with self.time_stage(gettext_noop("figures: timelines")):
            if not runs:
                return None
            weather_changes = [
                (
                    leg.start,
                    leg.weather.shown_short if leg.weather else _("weather unknown"),
                    leg.weather.icon if leg.weather else "",
                )
                for leg in self.legs[shift.id]
            ]
            return _name(
                draw_timeline(
                    runs,
                    self.reasons,
                    weather_changes,
                    self.tz,
                    # SVG: no rasterising and PNG encoding, and its text stays sharp.
                    str(self._file("timeline", ".svg")),
                    min_span=timedelta(hours=self.options.min_timeline_hours),
                )
            )

    def _shift(self, shift, f: Figures | None, runs, tick) -> dict:
        tz = self.tz
        # A leg's report spans the leg, not its whole shift.
        span = self.legs[shift.id][0] if self.options.leg else shift
        starts = [r.start for r in runs] + [span.start]
        ends = [r.end for r in runs] + ([span.end] if span.end else [])
        summary_rows = tables.label_rows(
            [
                (_("Shift"), str(shift.number)),
                *([(_("Leg"), str(span.number))] if self.options.leg else []),
                (_("Start"), fmt.timestamp(min(starts), tz)),
                (pgettext("time", "End"), fmt.timestamp(max(ends), tz) if span.end else _("open")),
                (_("Test director"), tables.person_text(shift.test_director)),
                (_("Test administrator"), tables.person_text(shift.test_administrator)),
                (_("Robot operator"), tables.person_text(shift.robot_operator)),
                (_("Safety officer"), tables.person_text(shift.safety_officer)),
                (_("Performer"), shift.performer.institution if shift.performer else fmt.DASH),
                (_("Vehicle"), shift.vehicle.short_description),
                (_("Test intent"), shift.test_intent or fmt.DASH),
                (_("Workspace"), shift.workspace or fmt.DASH),
                (_("Weather"), tables.weather_text(self.legs[shift.id])),
                (_("Note"), shift.note or fmt.DASH),
            ]
        )
        overview, overview_note = self.maps.draw(runs, shift, self._file, OVERVIEW_SIZE)
        timeline = self._timeline(shift, runs)
        tick(deferred(gettext_noop("shift %(number)s"), number=shift.number))
        legs = {leg.id: leg for leg in self.legs[shift.id]}
        segments = []
        level = self.options.level
        for index, run in enumerate(runs, start=1):
            if level == FULL or (level == STANDARD and run.kind == "ito"):
                segments.append(self._segment(run, legs[run.leg_id], full=level == FULL))
            tick(
                deferred(
                    gettext_noop("shift %(number)s, segment %(index)s"),
                    number=shift.number,
                    index=index,
                )
            )
        return {
            "title": f"{self.scope_name if self.options.leg else shift_name(shift.number)}: "
            + f"{fmt.timestamp(min(starts), tz)} – "
            + (fmt.timestamp(max(ends), tz) if span.end else _("open")),
            "summary": summary_rows,
            "figures": tables.figure_rows(f) if f is not None else [],
            "mode_rows": tables.mode_rows(f) if f is not None else [],
            "map": overview,
            "map_note": overview_note,
            "timeline": timeline,
            "timeline_note": "" if timeline else _("No segments to draw."),
            "segments": segments,
        }

    def _segment(self, run, leg, full: bool) -> dict:
        tz = self.tz
        spans = sorted(run.reasons, key=lambda s: (s.start, s.id))

        def joined(attr):
            values = [getattr(s, attr) for s in spans if getattr(s, attr)]
            return ", ".join(values) or fmt.DASH

        reasons = ", ".join(
            (_("%(reason)s (counted)") if s.reason in run.counted_reasons else "%(reason)s")
            % {
                "reason": self.reasons[s.reason].shown_short
                if s.reason in self.reasons
                else s.reason
            }
            for s in spans
        )
        rows = tables.label_rows(
            [
                (_("Segment"), run.label),
                (_("Type"), run.kind.upper()),
                (_("Start"), fmt.timestamp(run.start, tz)),
                (
                    pgettext("time", "End"),
                    fmt.timestamp(run.end, tz) + ((" " + _("(still open)")) if run.is_open else ""),
                ),
                (_("Duration"), fmt.duration(run.seconds)),
                (_("Distance"), fmt.metres(run.distance)),
                # GPS fixes without a position are not counted: say how many.
                (
                    _("Poses"),
                    _("%(count)s with a position, %(no_fix)s without a fix (left out)")
                    % {"count": run.pose_count, "no_fix": run.track.no_fix if run.track else 0}
                    if self.mode == GPS_TRACK
                    else str(run.pose_count),
                ),
                (_("Database id"), str(run.id)),
                (_("Reason(s)"), reasons or fmt.DASH),
                (_("Obstacle"), joined("obstacle")),
                (_("Lighting"), joined("lighting")),
                (_("Slope"), joined("slope")),
                (_("Weather"), leg.weather.shown_short if leg.weather else _("unknown")),
            ]
            + [
                (_("Snapshot"), f"{summary(r)}, {fmt.clock(r.start, tz)}–{fmt.clock(r.end, tz)}")
                for r in self.recordings.get(run.id, [])
            ]
        )
        notes = [
            {
                "author": note.author.name if note.author else _("unknown author"),
                "time": fmt.timestamp(note.created, tz),
                "text": note.text,
            }
            for note in self.notes.get(run.id, [])
        ]
        sketch = None
        if full:
            sketch = track_sketch(run.path_x, run.path_y, self.mode, *SKETCH_SIZE)
        return {
            "anchor": f"segment-{run.id}",
            "title": _("%(segment)s · %(mode)s at %(time)s")
            % {"segment": run.label, "mode": run.kind.upper(), "time": fmt.clock(run.start, tz)},
            "open": run.is_open,
            "rows": rows,
            "notes": notes,
            "sketch": sketch,
            "map_note": "" if sketch or not full else _("No positions recorded."),
            "images": self._images(run),
        }

    def _images(self, run) -> list[dict]:
        """A segment's camera frames; with the appendix, each links to its full size."""
        images = []
        for image in self.images.get(run.id, []):
            picture = self.pictures.camera(image)
            if picture is None:
                continue
            caption = image.description or _("Camera image")
            entry = {"thumb": picture[0], "caption": caption, "anchor": None}
            if self.options.image_appendix:
                entry["anchor"] = f"image-{len(self.appendix) + 1}"
                self.appendix.append(
                    {
                        "anchor": entry["anchor"],
                        "path": picture[1],
                        "caption": f"{run.label}: {caption}",
                        "segment": f"segment-{run.id}",
                    }
                )
            images.append(entry)
        return images

    def _methods(self, stats: EventStatistics, shifts) -> dict:
        number = {s.id: s.number for s in shifts}
        runs = stats.runs
        without_poses = [
            f"{shift_name(number[r.shift_id])}, {r.label} ({r.kind.upper()}) "
            f"({fmt.timestamp(r.start, self.tz)})"
            for r in runs
            if r.pose_count == 0
        ]
        gaps = []
        no_fix = 0
        for r in runs:
            if r.track is None:
                continue
            no_fix += r.track.no_fix
            for a, b in r.track.gaps:
                gaps.append(
                    f"{shift_name(number[r.shift_id])}, {r.label}: "
                    f"{fmt.timestamp(a, self.tz)} – {fmt.clock(b, self.tz)} "
                    f"({fmt.duration((b - a).total_seconds())})"
                )
        uncertain = [r.start_uncertainty for r in runs if r.start_uncertainty]
        no_start = [
            f"{shift_name(number[r.shift_id])}, {r.label}" for r in runs if not r.has_start_position
        ]
        counted = [self.reasons[k].shown_short for k in stats.counted_reasons if k in self.reasons]
        not_counted = [
            r.shown_short for k, r in sorted(self.reasons.items()) if k not in stats.counted_reasons
        ]
        return {
            "formulas": [list(pair) for pair in translated_definitions(FORMULAS).items()],
            "counted": counted,
            "not_counted": not_counted,
            "confidence": f"{round(CONFIDENCE * 100)} %",
            "time_zone": self.event.time_zone,
            "gap_seconds": fmt.number(GAP_SECONDS),
            "without_poses": without_poses,
            "gaps": gaps[:MAX_GAPS_LISTED],
            "gaps_more": max(0, len(gaps) - MAX_GAPS_LISTED),
            "no_fix": no_fix,
            "no_start": no_start,
            "uncertain_starts": len(uncertain),
            "unknown_mode": _("%(time)s and %(distance)s")
            % {
                "time": fmt.duration(stats.overall.unknown_seconds),
                "distance": fmt.metres(stats.overall.unknown_distance),
            },
            "fixes_missed": sum(leg.fixes_missed for legs in self.legs.values() for leg in legs),
            "uncertainty_max": fmt.decimal(max(uncertain, default=0), 1),
            "tiles": self.maps.tiles_note(),
            "fonts": _(FONT_NOTE),
            "warnings": self.warnings,
        }


def _position_mode(mode: str) -> str:
    return "GPS (WGS84)" if mode == GPS_TRACK else _("local map frame")


def _name(path) -> str | None:
    return None if path is None else Path(path).name
