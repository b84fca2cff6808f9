"""manage.py ftt_report: the PDF report of a test event, and its exports.

    manage.py ftt_report --test-event 3 -o report.pdf --name "Trial 3" --recipient ACME
    manage.py ftt_report --test-event 3 --csv segments.csv --geojson tracks.geojson --gpx t.gpx
    manage.py ftt_report --shift 5 -o shift.pdf     # one shift (or --leg ID: one leg)
    manage.py ftt_report --job 17        # worker for a report requested from the GUI
    manage.py ftt_report --test-event 3 --json figures.json   # figures with their provenance
    manage.py ftt_report --verify report.pdf   # (or figures.json) is the data still the same?
    manage.py ftt_report --compare 3 4 --route-leg 12 --route-case 2   # with a routes section

Without -o and without any export option the PDF goes to report.pdf.
"""

import sys
from datetime import date
from pathlib import Path

from django.conf import settings
from django.core.management.base import BaseCommand, CommandError
from django.utils.formats import number_format
from django.utils.translation import gettext, gettext_lazy

from common.numbers import short
from common.progress import ProgressBar
from events.models import Leg, Shift, TestEvent
from reports.charts.tiles import MAX_ZOOM
from reports.documents.comparison import render_comparison
from reports.documents.event_report import render_report
from reports.documents.options import FULL, LEVELS, ReportError, ReportOptions
from reports.models import Report
from reports.selectors import exports
from reports.selectors.disengagements import (
    disengagements_csv,
    events_in_month,
    events_in_reporting_year,
    mileage_csv,
    reporting_months,
    reporting_year_of,
)
from reports.selectors.provenance import json_report, verify_report
from reports.selectors.routes import DEFAULT_THRESHOLD
from reports.services.generation import route_option, run_job

# One line per change the check names (entries of reports.selectors.provenance).
_CHANGE_LINES = {
    "created": gettext_lazy("%(record)s created %(when)s by %(who)s via %(channel)s"),
    "changed": gettext_lazy("%(record)s changed %(when)s by %(who)s via %(channel)s"),
    "deleted": gettext_lazy("%(record)s deleted %(when)s by %(who)s via %(channel)s"),
}


class Command(BaseCommand):
    help = gettext("Make the PDF field-test report of a test event (and CSV/GeoJSON/GPX exports).")

    def create_parser(self, prog_name, subcommand, **kwargs):
        # --version is the report's version here, not Django's.
        kwargs.setdefault("conflict_handler", "resolve")
        return super().create_parser(prog_name, subcommand, **kwargs)

    def add_arguments(self, parser):
        parser.add_argument("--test-event", type=int, help=gettext("Id of the test event."))
        parser.add_argument("--shift", type=int, help=gettext("Report only this shift (id)."))
        parser.add_argument("--leg", type=int, help=gettext("Report only this leg (id)."))
        parser.add_argument("--job", type=int, help=gettext("Make the queued report with this id."))
        parser.add_argument(
            "-o", "--output", help=gettext("PDF file to write (default report.pdf).")
        )
        parser.add_argument(
            "--local", action="store_true", help=gettext("Use local (map-frame) poses.")
        )
        parser.add_argument("--name", default="", help=gettext("Report name on the title page."))
        parser.add_argument(
            "--version",
            dest="report_version",
            default="1.0",
            help=gettext("Report version on the title page."),
        )
        parser.add_argument("--recipient", default="", help=gettext("Prepared for: name."))
        parser.add_argument(
            "--recipient-address",
            action="append",
            default=[],
            help=gettext("Address line (repeat)."),
        )
        parser.add_argument("--creator", default="", help=gettext("Prepared by: name."))
        parser.add_argument(
            "--creator-address", action="append", default=[], help=gettext("Address line (repeat).")
        )
        parser.add_argument(
            "--logo", help=gettext("Logo image (PNG, JPEG or SVG) for the title page.")
        )
        parser.add_argument("--tile-url", help=gettext("Tile URL template with {z}/{x}/{y}."))
        parser.add_argument(
            "--no-tiles", action="store_true", help=gettext("Draw maps without tiles.")
        )
        parser.add_argument(
            "--min-timeline",
            type=float,
            default=0.0,
            metavar="HOURS",
            help=gettext("Draw each shift's timeline at least this long (the original's min_dur)."),
        )
        parser.add_argument(
            "--max-zoom",
            type=int,
            default=MAX_ZOOM,
            help=gettext("Never use map tiles closer than this zoom level (1-%(max)s).")
            % {"max": MAX_ZOOM},
        )
        parser.add_argument(
            "--compare",
            type=int,
            nargs="+",
            metavar="EVENT",
            help=gettext("Compare these test events (at least two) in one PDF instead."),
        )
        parser.add_argument(
            "--route-leg",
            type=int,
            action="append",
            default=[],
            metavar="LEG",
            help=gettext(
                "With --compare: add a routes section with this leg's GPS route (repeat; "
                "two routes or more, legs and --route-case together)."
            ),
        )
        parser.add_argument(
            "--route-case",
            type=int,
            action="append",
            default=[],
            metavar="CASE",
            help=gettext("With --compare: add this test case's planned route (repeat)."),
        )
        parser.add_argument(
            "--route-threshold",
            type=float,
            metavar="METRES",
            help=gettext(
                "With routes: draw stretches farther than this from the other route in red "
                "(default %(metres)s)."
            )
            % {"metres": short(DEFAULT_THRESHOLD)},
        )
        parser.add_argument(
            "--level",
            choices=[value for value, _ in LEVELS],
            default=FULL,
            help="; ".join(str(text) for _, text in LEVELS),
        )
        parser.add_argument(
            "--language",
            choices=[code for code, _ in settings.LANGUAGES],
            default="",
            help=gettext(
                "Language of the report (default: the test event's language; for "
                "--compare the one the test events share, else FTT_LANGUAGE)."
            ),
        )
        parser.add_argument(
            "--no-image-appendix",
            action="store_true",
            help=gettext(
                "Camera frames only as thumbnails, without full-size copies in an appendix."
            ),
        )
        parser.add_argument("--csv", help=gettext("Write the segments as CSV to this file."))
        parser.add_argument(
            "--geojson", help=gettext("Write the GPS tracks as GeoJSON to this file.")
        )
        parser.add_argument("--gpx", help=gettext("Write the GPS tracks as GPX to this file."))
        parser.add_argument(
            "--json",
            help=gettext("Write the figures with their provenance (digest) as JSON to this file."),
        )
        parser.add_argument(
            "--dmv",
            help=gettext(
                "Write the disengagement report (California DMV columns) as CSV to this file."
            ),
        )
        parser.add_argument(
            "--dmv-mileage",
            help=gettext(
                "Write the autonomous miles per vehicle and month of a reporting year "
                "(California DMV columns) as CSV to this file."
            ),
        )
        parser.add_argument(
            "--month",
            metavar="YYYY-MM",
            help=gettext("With --dmv and without --test-event: every test event of that month."),
        )
        parser.add_argument(
            "--year",
            type=int,
            metavar="YYYY",
            help=gettext(
                "With --dmv or --dmv-mileage: the DMV's reporting year, December of the "
                "year before to November (default with --test-event: the year of its start)."
            ),
        )
        parser.add_argument(
            "--verify",
            metavar="REPORT",
            help=gettext("Check a PDF or JSON report against the data: exit 1 when it changed."),
        )

    def handle(self, *args, **o):
        if o["verify"]:
            return self._verify(Path(o["verify"]))
        if o["job"] is not None:
            return self._job(o["job"])
        if (o["dmv"] or o["dmv_mileage"]) and o["test_event"] is None:
            return self._dmv_scope(o)
        if o["compare"]:
            return self._compare(o)
        if _routes_asked(o):
            raise CommandError(
                gettext("--route-leg, --route-case and --route-threshold go with --compare.")
            )
        event_id = o["test_event"] or _event_of(o["shift"], o["leg"])
        if event_id is None and (o["shift"] or o["leg"]):
            raise CommandError(
                gettext("No leg with this id.") if o["leg"] else gettext("No shift with this id.")
            )
        if event_id is None:
            raise CommandError(
                gettext("Give --test-event ID, --shift ID or --leg ID (or --job ID).")
            )
        event = TestEvent.objects.filter(pk=event_id).first()
        if event is None:
            raise CommandError(gettext("Test event %(id)s does not exist.") % {"id": event_id})
        exported = self._exports(event, o)
        if o["output"] or not exported:
            self._pdf(event, o)

    def _verify(self, path: Path):
        if not path.is_file():
            raise CommandError(gettext("%(path)s does not exist.") % {"path": path})
        verdict = verify_report(path.read_bytes())
        if verdict is None:
            raise CommandError(
                gettext("%(path)s carries no FTT data digest (made before FTT stamped it?).")
                % {"path": path}
            )
        line = gettext("OK: %(message)s") if verdict.ok else gettext("CHANGED: %(message)s")
        self.stdout.write(line % {"message": verdict.message})
        for change in verdict.changes:
            reason = f" ({change['reason']})" if change["reason"] else ""  # the author's words
            line = _CHANGE_LINES[change["kind"]] % {
                "record": change["record"],
                "when": change["at"],
                "who": change["by"] or "FTT",
                "channel": change["channel"],
            }
            self.stdout.write(f"  {line}{reason}")
        if not verdict.ok:
            raise CommandError(gettext("The data differs from the report."), returncode=1)

    @staticmethod
    def _month(o) -> tuple[int, int] | None:
        if not o["month"]:
            return None
        try:
            year, month = (int(part) for part in o["month"].split("-"))
            # The calendar's own range: years 1 to 9999, months 1 to 12.
            date(year, month, 1)
        except ValueError:
            raise CommandError(
                gettext("Give the month as YYYY-MM between 0001-01 and 9999-12, e.g. 2026-05.")
            ) from None
        return year, month

    @staticmethod
    def _year(o) -> int | None:
        year = o["year"]
        if year is not None and not 2 <= year <= 9999:
            raise CommandError(gettext("Give the reporting year between 0002 and 9999."))
        if year is not None and o["month"]:
            raise CommandError(gettext("Give --month or --year, not both."))
        return year

    def _months(self, o) -> set[tuple[int, int]] | None:
        year = self._year(o)
        if year is not None:
            return set(reporting_months(year))
        month = self._month(o)
        return None if month is None else {month}

    def _dmv_scope(self, o):
        """The DMV tables of every test event of a month or reporting year."""
        year, month = self._year(o), self._month(o)
        if o["dmv_mileage"] and year is None:
            raise CommandError(gettext("Give --year YYYY (or --test-event ID) with --dmv-mileage."))
        if year is None and month is None:
            raise CommandError(gettext("Give --test-event ID or --month YYYY-MM with --dmv."))
        events = events_in_month(*month) if month else events_in_reporting_year(year)
        if o["dmv"]:
            Path(o["dmv"]).write_text(disengagements_csv(events, self._months(o)), encoding="utf-8")
            self.stdout.write(gettext("disengagement report: %(file)s") % {"file": o["dmv"]})
        if o["dmv_mileage"]:
            Path(o["dmv_mileage"]).write_text(mileage_csv(events, year), encoding="utf-8")
            self.stdout.write(gettext("autonomous mileage: %(file)s") % {"file": o["dmv_mileage"]})

    def _compare(self, o):
        ids = o["compare"]
        events = list(TestEvent.objects.filter(pk__in=ids))
        missing = sorted(set(ids) - {e.pk for e in events})
        if missing:
            raise CommandError(gettext("Test event %(id)s does not exist.") % {"id": missing[0]})
        routes = _routes(o)
        try:
            pdf = render_comparison(
                events, "local" if o["local"] else "gps", o["language"], routes=routes
            )
        except ReportError as exc:
            raise CommandError(str(exc)) from exc
        output = Path(o["output"] or "comparison.pdf")
        output.write_bytes(pdf)
        self.stdout.write(
            gettext("comparison of %(count)s test events: %(file)s")
            % {"count": len(events), "file": output}
        )

    def _job(self, report_id: int):
        if not Report.objects.filter(pk=report_id).exists():
            raise CommandError(gettext("Report %(id)s does not exist.") % {"id": report_id})
        report = run_job(report_id)
        if report.status == Report.Status.FAILED:
            raise CommandError(report.shown_error)
        self.stdout.write(
            gettext("report %(id)s: %(file)s") % {"id": report_id, "file": report.pdf.name}
        )

    def _exports(self, event, o) -> bool:
        writers = (
            ("csv", lambda: exports.segments_csv_rows(event, "local" if o["local"] else "gps")),
            ("geojson", lambda: exports.tracks_geojson_pieces(event)),
            ("gpx", lambda: exports.tracks_gpx_pieces(event)),
            ("json", lambda: [json_report(event, "local" if o["local"] else "gps")]),
            ("dmv", lambda: [disengagements_csv([event], self._months(o))]),
            (
                "dmv_mileage",
                lambda: [
                    mileage_csv(
                        [event],
                        self._year(o) or reporting_year_of(event.start.astimezone(event.tzinfo)),
                    )
                ],
            ),
        )
        done = False
        for key, make in writers:
            if o[key]:
                with Path(o[key]).open("w", encoding="utf-8", newline="") as out:
                    out.writelines(make())
                self.stdout.write(gettext("%(kind)s: %(file)s") % {"kind": key, "file": o[key]})
                done = True
        return done

    def _pdf(self, event, o):
        options = ReportOptions(
            name=o["name"],
            version=o["report_version"],
            recipient=o["recipient"],
            recipient_address=o["recipient_address"],
            creator=o["creator"],
            creator_address=o["creator_address"],
            local=o["local"],
            tile_url=o["tile_url"],
            no_tiles=o["no_tiles"],
            logo=o["logo"],
            min_timeline_hours=o["min_timeline"],
            max_zoom=o["max_zoom"],
            level=o["level"],
            image_appendix=not o["no_image_appendix"],
            language=o["language"],
            shift=o["shift"],
            leg=o["leg"],
        )
        if problems := options.problems():
            raise CommandError(" ".join(problems))
        if options.logo and not Path(options.logo).is_file():
            raise CommandError(
                gettext("Logo file %(file)s does not exist.") % {"file": options.logo}
            )
        output = Path(o["output"] or "report.pdf")
        try:
            result = render_report(event, options, ProgressBar(o.get("stderr") or sys.stderr))
        except ReportError as exc:
            raise CommandError(str(exc)) from None
        output.write_bytes(result.pdf)
        for warning in result.warnings:
            self.stderr.write(gettext("warning: %(warning)s") % {"warning": warning})
        written = gettext("%(file)s: written in %(seconds)s s") % {
            "file": output,
            "seconds": number_format(result.seconds, 1),
        }
        note = gettext(" (provisional: open segments)") if result.provisional else ""
        self.stdout.write(written + note)
        if o["verbosity"] >= 2:
            self._print_stages(result)

    def _print_stages(self, result) -> None:
        """Where the time went, for an administrator whose report is slow."""
        rows = result.stages.rows()
        for stage, wall, cpu in rows:
            self.stderr.write(
                gettext("%(stage)s: %(seconds)s s (CPU %(cpu)s s)")
                % {
                    "stage": gettext(stage),
                    "seconds": number_format(wall, 2),
                    "cpu": number_format(cpu, 2),
                }
            )
        rest = result.seconds - sum(wall for _stage, wall, _cpu in rows)
        self.stderr.write(
            gettext("the rest (tables, texts): %(seconds)s s") % {"seconds": number_format(rest, 2)}
        )


def _routes_asked(o) -> bool:
    return bool(o["route_leg"] or o["route_case"]) or o["route_threshold"] is not None


def _routes(o) -> dict | None:
    """The comparison's routes option from --route-*, checked as a request's is."""
    if not _routes_asked(o):
        return None
    value = {"leg": o["route_leg"], "case": o["route_case"]}
    if o["route_threshold"] is not None:
        value["threshold"] = o["route_threshold"]
    errors = []
    routes = route_option(value, errors)
    if errors:
        raise CommandError(" ".join(errors))
    return routes


def _event_of(shift: int | None, leg: int | None) -> int | None:
    """The test event of the shift or leg asked for (None: none given or unknown)."""
    if leg is not None:
        return Leg.objects.filter(pk=leg).values_list("shift__test_event_id", flat=True).first()
    if shift is not None:
        return Shift.objects.filter(pk=shift).values_list("test_event_id", flat=True).first()
    return None
