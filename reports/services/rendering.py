"""Building the PDF report of a test event: data, figures, typst.

User text never passes through markup: the typst template receives one JSON
document (``sys.inputs.data``) and places its strings as plain text, so any
character, from umlauts and CJK to ``#``, ``$``, ``\\`` or ``<b>``, appears as
written.  All times are shown in the test event's time zone.
"""

import hashlib
import io
import json
import shutil
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import date, timedelta
from pathlib import Path

import numpy as np
import typst
from django.conf import settings
from django.utils import timezone
from PIL import Image as PILImage

from basemaps.selectors.layers import default_layer
from events.models import ItoReason, Note, Segment, TestEvent
from reports import formatting as fmt
from reports.figures import charts, style
from reports.figures.maps import Background, Line, MapPainter
from reports.figures.sketch import track_sketch
from reports.figures.tiles import MAX_ZOOM, LayerTiles, TileSource
from reports.figures.timeline import draw_timeline
from reports.selectors.statistics import (
    CONFIDENCE,
    FORMULAS,
    EventStatistics,
    Figures,
    event_statistics,
)
from telemetry.models import Image
from telemetry.selectors.maps import current_map
from telemetry.selectors.recordings import recordings_by_master, summary
from telemetry.selectors.tracks import GAP_SECONDS, GPS, LOCAL

TEMPLATE_DIR = Path(__file__).resolve().parent.parent / "templates_typst"
DEFAULT_LOGO = TEMPLATE_DIR / "logo.svg"
FONT_NOTE = (
    "DejaVu Sans with WenQuanYi Micro Hei or Noto CJK for Chinese, Japanese and Korean, "
    "and Noto Color Emoji for emoji"
)

Progress = Callable[[float, str], None]
MAX_TIMELINE_HOURS = 48

# How much of each shift the report shows: the GUI dialog, the API and the
# command offer these choices (value, what a person reads).
SUMMARY, STANDARD, FULL = "summary", "standard", "full"
LEVELS = (
    (SUMMARY, "Summary: event and shift pages only"),
    (STANDARD, "Standard: plus one compact block per intervention (ITO)"),
    (FULL, "Full: every segment with its map"),
)
THUMBNAIL_PX = 480
FULL_IMAGE_PX = 1600
# Points: the size of a segment's map sketch.
SKETCH_SIZE = (190.0, 135.0)


class ReportError(Exception):
    """The report cannot be made; the message says why in words for a person."""


@dataclass
class ReportOptions:
    name: str = ""
    version: str = "1.0"
    recipient: str = ""
    recipient_address: list[str] = field(default_factory=list)
    creator: str = ""
    creator_address: list[str] = field(default_factory=list)
    local: bool = False
    tile_url: str | None = None  # None: the site's FTT_TILE_URL
    no_tiles: bool = False
    logo: str | None = None
    # The original's min_dur: a short shift's timeline still spans this many
    # hours, so timelines of several reports can be compared by eye.
    min_timeline_hours: float = 0.0
    # The original's zoom_level, as an upper bound: the zoom is still fitted to
    # each track, but never closer than this (a tile server may stop at 17).
    max_zoom: int = MAX_ZOOM
    level: str = FULL
    # Camera frames appear as thumbnails; with this each links to a full-size
    # copy in an appendix (without it the report stays shorter).
    image_appendix: bool = True

    def problems(self) -> list[str]:
        """What is out of range, in words for the person who asked."""
        found = []
        if not 0 <= self.min_timeline_hours <= MAX_TIMELINE_HOURS:
            found.append(
                f"The minimum timeline length must be between 0 and {MAX_TIMELINE_HOURS} hours."
            )
        if not 1 <= self.max_zoom <= MAX_ZOOM:
            found.append(f"The maximum map zoom must be between 1 and {MAX_ZOOM}.")
        if self.level not in dict(LEVELS):
            found.append(f"The level must be one of {', '.join(dict(LEVELS))}.")
        return found

    @classmethod
    def from_dict(cls, data: dict) -> "ReportOptions":
        known = {k: v for k, v in (data or {}).items() if k in cls.__dataclass_fields__}
        return cls(**known)

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass
class ReportResult:
    pdf: bytes
    pages_hint: int
    provisional: bool
    tiles_used: bool
    seconds: float
    warnings: list[str]
    # Wall and CPU seconds per stage (statistics, figures, images, typst), for the benchmark.
    stages: dict[str, float] = field(default_factory=dict)
    cpu_stages: dict[str, float] = field(default_factory=dict)


class Stages:
    """Wall and CPU seconds per stage of a report, for the benchmark's breakdown.
    CPU seconds (all threads of this process) vary far less with the machine's
    load than wall seconds."""

    def __init__(self):
        self.wall: dict[str, float] = defaultdict(float)
        self.cpu: dict[str, float] = defaultdict(float)

    @contextmanager
    def timed(self, name: str):
        wall, cpu = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.wall[name] += time.perf_counter() - wall
            self.cpu[name] += time.process_time() - cpu


def _silent(_fraction: float, _message: str) -> None:
    pass


def check_reportable(event: TestEvent) -> None:
    if not Segment.objects.filter(leg__shift__test_event=event).exists():
        raise ReportError(
            f"Test event {event.pk} ('{event}') has no segments yet: nothing to report."
        )


def render_report(
    event: TestEvent, options: ReportOptions, progress: Progress = _silent
) -> ReportResult:
    """The finished PDF as bytes; raises ReportError for a test event without data."""
    started = time.perf_counter()
    check_reportable(event)
    style.apply()
    with tempfile.TemporaryDirectory(prefix="ftt-report-") as tmp:
        builder = _Builder(event, options, Path(tmp), progress)
        data = builder.build()
        progress(0.95, "typesetting")
        shutil.copy(TEMPLATE_DIR / "report.typ", Path(tmp) / "report.typ")
        with builder.stages.timed("typst"):
            try:
                pdf = typst.compile(
                    str(Path(tmp) / "report.typ"),
                    root=tmp,
                    sys_inputs={"data": json.dumps(data, ensure_ascii=False)},
                )
            except typst.TypstError as exc:  # a template bug, never user text
                raise ReportError(f"Typesetting failed: {exc}") from exc
    progress(1.0, "done")
    return ReportResult(
        pdf=pdf,
        pages_hint=len(data["shifts"]),
        provisional=data["provisional"],
        tiles_used=builder.tiles_used,
        seconds=time.perf_counter() - started,
        warnings=builder.warnings,
        stages=dict(builder.stages.wall),
        cpu_stages=dict(builder.stages.cpu),
    )


def _kv(pairs):
    return [[label, value] for label, value in pairs]


def _people(person) -> str:
    if person is None:
        return fmt.DASH
    return f"{person.name} ({person.institution})" if person.institution else person.name


class _Builder:
    def __init__(self, event, options: ReportOptions, root: Path, progress: Progress):
        self.event = event
        self.options = options
        self.root = root
        self.progress = progress
        self.tz = event.tzinfo
        self.mode = LOCAL if options.local else GPS
        self.warnings: list[str] = []
        self.tiles_used = False
        self.reasons = {r.key: r for r in ItoReason.objects.all()}
        self.tiles = self._tile_source(event, options)
        self.painter = MapPainter(tiles=self.tiles)
        self.figure_count = 0
        self.pictures: dict[str, tuple[str, str] | None] = {}  # content hash: (thumb, full)
        self.appendix: list[dict] = []
        self.stages = Stages()

    def _tile_source(self, event, options: ReportOptions) -> TileSource | None:
        """A tile URL given for this report, else the event's basemap, else the site's."""
        if options.no_tiles or self.mode == LOCAL:
            return None
        tile_url = options.tile_url
        if tile_url is None:
            layer = default_layer(event.pk)
            if layer is not None and layer.served_by_ftt:
                return LayerTiles(layer, max_zoom=options.max_zoom)
            tile_url = layer.url if layer is not None else settings.FTT_TILE_URL
        if not tile_url:
            return None
        cache = Path(getattr(settings, "FTT_TILE_CACHE", settings.DATA_DIR / "tile_cache"))
        return TileSource(tile_url, cache, max_zoom=options.max_zoom)

    # --- helpers ---------------------------------------------------------------------------

    def _file(self, stem: str, suffix: str = ".png") -> Path:
        self.figure_count += 1
        return self.root / f"{stem}-{self.figure_count}{suffix}"

    def _rel(self, path: Path | str | None) -> str | None:
        return None if path is None else Path(path).name

    def _lines(self, runs) -> list[Line]:
        return [
            Line(run.path_x, run.path_y, self._type_color(run.kind))
            for run in runs
            if len(run.path_x)
        ]

    def _type_color(self, kind: str) -> str:
        return "44,160,44" if kind == "auto" else "214,39,40"

    def _map(self, runs, shift, painter, size) -> tuple[str | None, str]:
        with self.stages.timed("figures: maps"):
            return self._draw_map(runs, shift, painter, size)

    def _draw_map(self, runs, shift, painter, size) -> tuple[str | None, str]:
        lines = self._lines(runs)
        if not lines:
            return None, "No positions recorded."
        path = self._file("map")
        if self.mode == GPS:
            result = painter.gps_map(lines, str(path), size=size)
        else:
            result = painter.local_map(lines, self._background(shift), str(path), size=size)
        if result is None:
            return None, "No positions recorded."
        if self.mode == GPS and result.tiles:
            self.tiles_used = True
        return self._rel(result.path), result.note

    def _background(self, shift) -> Background | None:
        cache = getattr(self, "_backgrounds", {})
        self._backgrounds = cache
        if shift.id not in cache:
            map_image = current_map(shift)
            background = None
            if map_image is not None:
                try:
                    with map_image.image.open("rb") as fh:
                        array = np.asarray(PILImage.open(fh).convert("L"))
                    background = Background(
                        array,
                        map_image.resolution,
                        map_image.origin_x,
                        map_image.origin_y,
                        map_image.origin_yaw,
                    )
                except (OSError, ValueError) as exc:
                    self.warnings.append(f"Shift {shift.number}: map image unreadable ({exc}).")
            cache[shift.id] = background
        return cache[shift.id]

    # --- document --------------------------------------------------------------------------

    def build(self) -> dict:
        event = self.event
        self.progress(0.02, "statistics")
        with self.stages.timed("statistics (queries and distances)"):
            stats = event_statistics(event, self.mode)
        shifts = list(
            event.shifts.select_related(
                "vehicle",
                "performer",
                "test_director",
                "test_administrator",
                "safety_officer",
                "robot_operator",
            ).order_by("start", "id")
        )
        self.legs = defaultdict(list)
        for shift in shifts:
            self.legs[shift.id] = list(shift.legs.select_related("weather").order_by("start", "id"))
        self.notes = self._notes()
        self.images = self._images()
        self.recordings = recordings_by_master(segment__leg__shift__test_event=self.event)
        runs_by_shift = stats.runs_by_shift()
        total_steps = 2 + len(shifts) + len(stats.runs)
        self.step = 0

        def tick(message):
            self.step += 1
            self.progress(0.05 + 0.9 * self.step / total_steps, message)

        tick("global statistics")
        global_section = self._global(stats, shifts)
        shift_sections = []
        for shift in shifts:
            runs = runs_by_shift.get(shift.id, [])
            shift_sections.append(self._shift(shift, stats.by_shift.get(shift.id), runs, tick))
        return {
            "title": self._title(),
            "provisional": stats.provisional,
            "event": self._event_rows(stats),
            "mode": "GPS (WGS84)" if self.mode == GPS else "local map frame",
            "global": global_section,
            "shifts": shift_sections,
            "level": self.options.level,
            "appendix": self.appendix,
            "methods": self._methods(stats, shifts),
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
            self.warnings.append(f"Logo {logo} not found; the title page has none.")
        return {
            "name": o.name or f"Field test report: {self.event}",
            "version": o.version,
            "recipient": o.recipient,
            "recipient_address": list(o.recipient_address),
            "creator": o.creator,
            "creator_address": list(o.creator_address),
            "date": date.today().isoformat(),
            "generated": fmt.timestamp(timezone.now(), self.tz),
            "logo": logo_name,
        }

    def _event_rows(self, stats: EventStatistics) -> list:
        e = self.event
        return _kv(
            [
                ("Test event", str(e.pk)),
                ("Location", e.location or fmt.DASH),
                ("Software version", e.version or fmt.DASH),
                ("Start", fmt.timestamp(e.start, self.tz)),
                ("End", fmt.timestamp(e.end, self.tz) if e.end else "open"),
                ("Time zone", e.time_zone),
                ("Positions", "GPS (WGS84)" if self.mode == GPS else "local map frame"),
                ("Note", e.note or fmt.DASH),
            ]
        )

    def _figure_rows(self, f: Figures) -> list:
        conf = f"{round(CONFIDENCE * 100)} %"
        return _kv(
            [
                ("Total distance", fmt.metres(f.total_distance)),
                ("Autonomous distance", fmt.metres(f.auto_distance)),
                ("Manual (ITO) distance", fmt.metres(f.manual_distance)),
                ("Autonomy by distance", fmt.percent(f.autonomy_ratio_distance)),
                ("Autonomous time", fmt.duration(f.auto_seconds)),
                ("Manual (ITO) time", fmt.duration(f.manual_seconds)),
                ("Autonomy by time", fmt.percent(f.autonomy_ratio_time)),
                ("Autonomous runs", str(f.auto_runs)),
                ("Mean autonomous run", fmt.metres(f.mean_auto_run)),
                ("Longest autonomous run", fmt.metres(f.max_auto_run)),
                ("Interventions", str(f.interventions)),
                ("MDBI", fmt.estimate(f.mdbi, fmt.metres)),
                (f"MDBI {conf} bounds", fmt.bounds(f.mdbi, fmt.metres)),
                ("MTBI", fmt.estimate(f.mtbi, fmt.duration)),
                (f"MTBI {conf} bounds", fmt.bounds(f.mtbi, fmt.duration)),
                ("Interventions per km", fmt.rate(f.interventions_per_km)),
                ("Interventions per hour", fmt.rate(f.interventions_per_hour)),
            ]
        )

    def _weather(self, shift) -> str:
        names = []
        for leg in self.legs[shift.id]:
            label = leg.weather.short_description if leg.weather else "unknown"
            if not names or names[-1] != label:
                names.append(label)
        return ", ".join(names) or "unknown"

    def _reliability_row(self, label, f: Figures) -> list:
        return [
            label,
            str(f.interventions),
            fmt.estimate(f.mdbi, fmt.metres),
            fmt.bounds(f.mdbi, fmt.metres),
            fmt.estimate(f.mtbi, fmt.duration),
            fmt.bounds(f.mtbi, fmt.duration),
            fmt.rate(f.interventions_per_km),
            fmt.rate(f.interventions_per_hour),
        ]

    def _distance_cells(self, f: Figures) -> list:
        return [
            fmt.metres(f.total_distance),
            fmt.metres(f.auto_distance),
            fmt.percent(f.autonomy_ratio_distance),
            fmt.percent(f.autonomy_ratio_time),
            fmt.metres(f.mean_auto_run),
            fmt.metres(f.max_auto_run),
        ]

    def _global(self, stats: EventStatistics, shifts) -> dict:
        empty = stats.overall  # same shape, used for shifts without runs
        labels = [f"Shift {s.number}" for s in shifts]
        per_shift = [stats.by_shift.get(s.id, empty) for s in shifts]
        has = [s.id in stats.by_shift for s in shifts]
        distance_rows = []
        reliability_rows = []
        for shift, f, present in zip(shifts, per_shift, has, strict=True):
            head = [f"Shift {shift.number}", shift.vehicle.short_description, self._weather(shift)]
            if not present:
                distance_rows.append(head + [fmt.DASH] * 6)
                reliability_rows.append(head[:1] + [fmt.DASH] * 7)
                continue
            distance_rows.append(head + self._distance_cells(f))
            reliability_rows.append(self._reliability_row(head[0], f))
        o = stats.overall
        distance_rows.append(["Test event", "", ""] + self._distance_cells(o))
        reliability_rows.append(self._reliability_row("Test event", o))
        vehicles = {s.vehicle_id: s.vehicle for s in shifts}
        vehicle_rows = [
            self._reliability_row(vehicles[vid].short_description, f)
            for vid, f in stats.by_vehicle.items()
        ]
        reason_rows = []
        for key in sorted(
            set(o.manual_seconds_by_reason) | set(o.interventions_by_reason),
            key=lambda k: self.reasons[k].short_description if k in self.reasons else k,
        ):
            reason = self.reasons.get(key)
            reason_rows.append(
                [
                    reason.short_description if reason else key,
                    "yes" if key in stats.counted_reasons else "no",
                    str(o.interventions_by_reason.get(key, 0)),
                    fmt.duration(o.manual_seconds_by_reason.get(key, 0.0)),
                ]
            )
        present = [(lab, f) for lab, f, p in zip(labels, per_shift, has, strict=True) if p]
        with self.stages.timed("figures: charts"):
            charts_out = self._charts(present)
        return {
            "summary": self._figure_rows(o),
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
            charts.distance_chart(
                names,
                [f.auto_distance for _, f in present],
                [f.manual_distance for _, f in present],
                str(self._file("distance", ".svg")),
            ),
            charts.reasons_chart(
                names,
                [f.interventions_by_reason for _, f in present],
                self.reasons,
                str(self._file("reasons", ".svg")),
            ),
        ) + tuple(
            charts.estimate_chart(
                names,
                [getattr(f, key) for _, f in present],
                str(self._file(key, ".svg")),
                key.upper(),
                unit,
                scale=scale,
            )
            for key, unit, scale in (("mdbi", "m", 1.0), ("mtbi", "h", 3600.0))
        )
        return [self._rel(path) for path in made]

    def _shift(self, shift, f: Figures | None, runs, tick) -> dict:
        tz = self.tz
        starts = [r.start for r in runs] + [shift.start]
        ends = [r.end for r in runs] + ([shift.end] if shift.end else [])
        summary = _kv(
            [
                ("Shift", str(shift.number)),
                ("Start", fmt.timestamp(min(starts), tz)),
                ("End", fmt.timestamp(max(ends), tz) if shift.end else "open"),
                ("Test director", _people(shift.test_director)),
                ("Test administrator", _people(shift.test_administrator)),
                ("Robot operator", _people(shift.robot_operator)),
                ("Safety officer", _people(shift.safety_officer)),
                ("Performer", shift.performer.institution if shift.performer else fmt.DASH),
                ("Vehicle", shift.vehicle.short_description),
                ("Test intent", shift.test_intent or fmt.DASH),
                ("Workspace", shift.workspace or fmt.DASH),
                ("Weather", self._weather(shift)),
                ("Note", shift.note or fmt.DASH),
            ]
        )
        mode_rows = []
        if f is not None:
            for label, count, seconds, distance, extra in (
                ("AUTO", f.auto_runs, f.auto_seconds, f.auto_distance, fmt.DASH),
                ("ITO", f.ito_runs, f.manual_seconds, f.manual_distance, str(f.interventions)),
            ):
                kmh = fmt.DASH if seconds <= 0 else f"{distance / seconds * 3.6:.2f} km/h"
                mode_rows.append(
                    [
                        label,
                        str(count),
                        extra,
                        fmt.duration(seconds),
                        fmt.metres(distance),
                        fmt.speed(distance, seconds),
                        kmh,
                    ]
                )
        overview, overview_note = self._map(runs, shift, self.painter, (6.5, 4.8))
        timeline = None
        with self.stages.timed("figures: timelines"):
            if runs:
                weather_changes = [
                    (
                        leg.start,
                        leg.weather.short_description if leg.weather else "weather unknown",
                        leg.weather.icon if leg.weather else "",
                    )
                    for leg in self.legs[shift.id]
                ]
                timeline = self._rel(
                    draw_timeline(
                        runs,
                        self.reasons,
                        weather_changes,
                        tz,
                        # SVG: no rasterising and PNG encoding, and its text stays sharp.
                        str(self._file("timeline", ".svg")),
                        min_span=timedelta(hours=self.options.min_timeline_hours),
                    )
                )
        tick(f"shift {shift.number}")
        legs = {leg.id: leg for leg in self.legs[shift.id]}
        segments = []
        level = self.options.level
        for index, run in enumerate(runs, start=1):
            if level == FULL or (level == STANDARD and run.kind == "ito"):
                segments.append(self._segment(run, legs[run.leg_id], full=level == FULL))
            tick(f"shift {shift.number}, segment {index}")
        return {
            "title": f"Shift {shift.number}: {fmt.timestamp(min(starts), tz)} – "
            + (fmt.timestamp(max(ends), tz) if shift.end else "open"),
            "summary": summary,
            "figures": self._figure_rows(f) if f is not None else [],
            "mode_rows": mode_rows,
            "map": overview,
            "map_note": overview_note,
            "timeline": timeline,
            "timeline_note": "" if timeline else "No segments to draw.",
            "segments": segments,
        }

    def _segment(self, run, leg, full: bool) -> dict:
        tz = self.tz
        spans = sorted(run.reasons, key=lambda s: (s.start, s.id))

        def joined(attr):
            values = [getattr(s, attr) for s in spans if getattr(s, attr)]
            return ", ".join(values) or fmt.DASH

        reasons = ", ".join(
            (self.reasons[s.reason].short_description if s.reason in self.reasons else s.reason)
            + (" (counted)" if s.reason in run.counted_reasons else "")
            for s in spans
        )
        rows = _kv(
            [
                ("Segment", run.label),
                ("Type", run.kind.upper()),
                ("Start", fmt.timestamp(run.start, tz)),
                ("End", fmt.timestamp(run.end, tz) + (" (still open)" if run.is_open else "")),
                ("Duration", fmt.duration(run.seconds)),
                ("Distance", fmt.metres(run.distance)),
                ("Poses", str(run.pose_count)),
                ("Database id", str(run.id)),
                ("Reason(s)", reasons or fmt.DASH),
                ("Obstacle", joined("obstacle")),
                ("Lighting", joined("lighting")),
                ("Slope", joined("slope")),
                ("Weather", leg.weather.short_description if leg.weather else "unknown"),
            ]
            + [
                ("Snapshot", f"{summary(r)}, {fmt.clock(r.start, tz)}–{fmt.clock(r.end, tz)}")
                for r in self.recordings.get(run.id, [])
            ]
        )
        notes = [
            {
                "author": note.author.name if note.author else "unknown author",
                "time": fmt.timestamp(note.created, tz),
                "text": note.text,
            }
            for note in self.notes.get(run.id, [])
        ]
        sketch = None
        if full:
            sketch = track_sketch(run.path_x, run.path_y, self.mode, *SKETCH_SIZE)
        images = []
        for image in self.images.get(run.id, []):
            picture = self._picture(image)
            if picture is None:
                continue
            caption = image.description or "Camera image"
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
        return {
            "anchor": f"segment-{run.id}",
            "title": f"{run.label} · {run.kind.upper()} at {fmt.clock(run.start, tz)}",
            "open": run.is_open,
            "rows": rows,
            "notes": notes,
            "sketch": sketch,
            "map_note": "" if sketch or not full else "No positions recorded.",
            "images": images,
        }

    def _picture(self, image: Image) -> tuple[str, str] | None:
        """(thumbnail, full-size) file names; each distinct picture is decoded once."""
        try:
            with image.image.open("rb") as fh:
                content = fh.read()
        except OSError as exc:
            self.warnings.append(f"Image {image.pk} unreadable ({exc}); left out.")
            return None
        digest = hashlib.sha256(content).hexdigest()[:20]
        if digest not in self.pictures:
            with self.stages.timed("image encoding"):
                self.pictures[digest] = self._encode(image.pk, content, digest)
        return self.pictures[digest]

    def _encode(self, pk: int, content: bytes, digest: str) -> tuple[str, str] | None:
        try:
            picture = PILImage.open(io.BytesIO(content))
            picture.draft("RGB", (FULL_IMAGE_PX, FULL_IMAGE_PX))
            picture = picture.convert("RGB")
        except (OSError, ValueError) as exc:
            self.warnings.append(f"Image {pk} unreadable ({exc}); left out.")
            return None
        names = []
        sizes = [("thumb", THUMBNAIL_PX)]
        if self.options.image_appendix:
            sizes.append(("full", FULL_IMAGE_PX))
        for kind, size in sizes:
            copy = picture.copy()
            copy.thumbnail((size, size))
            name = f"img-{digest}-{kind}.jpg"
            copy.save(self.root / name, "JPEG", quality=82)
            names.append(name)
        return names[0], names[-1]

    def _notes(self) -> dict[int, list[Note]]:
        grouped = defaultdict(list)
        for note in (
            Note.objects.filter(segment__leg__shift__test_event=self.event)
            .select_related("author", "segment")
            .order_by("created", "id")
        ):
            grouped[note.segment.parent_id or note.segment_id].append(note)
        return grouped

    def _images(self) -> dict[int, list[Image]]:
        grouped = defaultdict(list)
        for image in Image.objects.filter(segment__leg__shift__test_event=self.event).order_by(
            "robot_stamp", "received", "id"
        ):
            grouped[image.segment_id].append(image)
        return grouped

    def _methods(self, stats: EventStatistics, shifts) -> dict:
        number = {s.id: s.number for s in shifts}
        runs = stats.runs
        without_poses = [
            f"Shift {number[r.shift_id]}, {r.label} ({r.kind.upper()}) "
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
                    f"Shift {number[r.shift_id]}, {r.label}: "
                    f"{fmt.timestamp(a, self.tz)} – {fmt.clock(b, self.tz)} "
                    f"({fmt.duration((b - a).total_seconds())})"
                )
        no_start = [
            f"Shift {number[r.shift_id]}, {r.label}" for r in runs if not r.has_start_position
        ]
        counted = [
            self.reasons[k].short_description for k in stats.counted_reasons if k in self.reasons
        ]
        not_counted = [
            r.short_description
            for k, r in sorted(self.reasons.items())
            if k not in stats.counted_reasons
        ]
        tiles = ""
        if self.mode == GPS:
            if self.tiles is None:
                tiles = (
                    "Map tiles were switched off: maps show a plain background with a "
                    "metric grid, scale bar and north arrow."
                )
            elif not self.tiles_used:
                tiles = (
                    "Map tiles were unavailable (tile server unreachable): maps show a plain "
                    "background with a metric grid, scale bar and north arrow."
                )
            elif isinstance(self.tiles, LayerTiles):
                tiles = f"Map: {self.tiles.url}, drawn by FTT from its own basemap file."
            else:
                tiles = (
                    f"Map tiles: {self.tiles.url} ({self.tiles.fetched} fetched, "
                    f"{self.tiles.from_cache} from the local cache). Map data © their owners, "
                    "e.g. OpenStreetMap contributors."
                )
        return {
            "formulas": [list(pair) for pair in FORMULAS],
            "counted": counted,
            "not_counted": not_counted,
            "confidence": f"{round(CONFIDENCE * 100)} %",
            "time_zone": self.event.time_zone,
            "gap_seconds": f"{GAP_SECONDS:g}",
            "without_poses": without_poses,
            "gaps": gaps[:200],
            "gaps_more": max(0, len(gaps) - 200),
            "no_fix": no_fix,
            "no_start": no_start,
            "tiles": tiles,
            "fonts": FONT_NOTE,
            "warnings": self.warnings,
        }
