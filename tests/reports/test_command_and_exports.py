"""manage.py ftt_report and the CSV / GeoJSON / GPX exports."""

import csv
import io
import json
from xml.etree import ElementTree as ET

import pytest
from django.core.management import CommandError, call_command
from pypdf import PdfReader

from events.services import logs
from tests.support.images import png
from tests.support.scenario import HOSTILE, STEP_M


def test_command_writes_the_pdf(scenario, tmp_path, settings):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    out = tmp_path / "out" / "bericht.pdf"
    out.parent.mkdir()
    stdout = io.StringIO()
    call_command(
        "ftt_report",
        "--test-event",
        str(scenario.event.pk),
        "--name",
        "Feldtest März",
        "--version",
        "3.0",
        "--recipient",
        "ACME",
        "--recipient-address",
        "Line 1",
        "--no-tiles",
        "-o",
        str(out),
        stdout=stdout,
    )
    reader = PdfReader(str(out))
    assert len(reader.pages) > 5
    first = reader.pages[0].extract_text()
    assert "Feldtest März" in first and "Version 3.0" in first and "ACME" in first
    assert f"{out}: written in" in stdout.getvalue()


def test_verbosity_2_says_where_the_report_spent_its_time(scenario, tmp_path):
    stdout, stderr = io.StringIO(), io.StringIO()
    call_command(
        "ftt_report", "--test-event", str(scenario.event.pk), "--no-tiles",
        "-o", str(tmp_path / "r.pdf"), "-v", "2", stdout=stdout, stderr=stderr,
    )  # fmt: skip
    total = float(stdout.getvalue().split("written in ")[1].split(" s")[0])
    seconds = {}
    for line in stderr.getvalue().splitlines():
        if line.endswith(" s)") or line.startswith("the rest"):
            stage, rest = line.rsplit(": ", 1)
            seconds[stage] = float(rest.split(" s")[0])
    assert {"statistics (queries and distances)", "figures: maps", "typesetting"} <= set(seconds)
    assert "the rest (tables, texts)" in seconds
    assert sum(seconds.values()) == pytest.approx(total, abs=0.1)


def test_unknown_test_event_is_a_clear_error(db):
    with pytest.raises(CommandError, match="Test event 999999 does not exist"):
        call_command("ftt_report", "--test-event", "999999")


def test_empty_test_event_is_a_clear_error(db, tmp_path):
    event = logs.create_test_event(location="leer")
    with pytest.raises(CommandError, match="has no segments yet"):
        call_command("ftt_report", "--test-event", str(event.pk), "-o", str(tmp_path / "x.pdf"))
    assert not (tmp_path / "x.pdf").exists()


def test_missing_logo_is_a_clear_error(scenario, tmp_path):
    with pytest.raises(CommandError, match="Logo file .* does not exist"):
        call_command(
            "ftt_report", "--test-event", str(scenario.event.pk), "--logo", "/nonexistent.png"
        )


def test_exports_from_the_command(scenario, tmp_path):
    paths = {k: tmp_path / f"x.{k}" for k in ("csv", "geojson", "gpx")}
    call_command(
        "ftt_report",
        "--test-event",
        str(scenario.event.pk),
        "--csv",
        str(paths["csv"]),
        "--geojson",
        str(paths["geojson"]),
        "--gpx",
        str(paths["gpx"]),
        stdout=io.StringIO(),
    )
    assert not (tmp_path / "report.pdf").exists()  # only exports were asked for

    rows = list(csv.DictReader(paths["csv"].open(encoding="utf-8")))
    masters = [r for r in rows if r["row"] == "master"]
    reasons = [r for r in rows if r["row"] == "reason"]
    assert len(masters) == 7 and len(reasons) == 4
    a1 = next(r for r in masters if int(r["segment_id"]) == scenario.masters["A1"].id)
    assert float(a1["distance_m"]) == pytest.approx(3 * STEP_M, abs=1e-3)
    assert a1["start"] == "2026-03-02T10:00:00+09:00"  # Tokyo time
    safety = next(r for r in reasons if r["reason"] == "safety")
    assert safety["obstacle"] == HOSTILE and safety["counts_as_intervention"] == "yes"
    assert safety["robot_operator"] == scenario.people["operator"].name
    i1 = next(r for r in masters if int(r["segment_id"]) == scenario.masters["I1"].id)
    assert HOSTILE in i1["notes"]
    # The GUI's numbering: I1 is the second master of its leg, safety its first reason.
    assert i1["label"] == "Leg 1 · #2" and safety["label"] == "Leg 1 · #2.1"

    features = json.loads(paths["geojson"].read_text(encoding="utf-8"))["features"]
    assert len(features) == 7
    a3 = next(f for f in features if f["properties"]["segment_id"] == scenario.masters["A3"].id)
    coords = a3["geometry"]["coordinates"]
    # start, three poses, next segment's start
    assert [round(lon, 4) for lon, _ in coords] == [0.01, 0.011, 0.012, 0.013, 0.014]

    gpx = ET.parse(paths["gpx"]).getroot()
    ns = {"g": "http://www.topografix.com/GPX/1/1"}
    tracks = gpx.findall("g:trk", ns)
    assert len(tracks) == 6  # I2 has no poses
    first_times = [t.find("g:trkseg/g:trkpt/g:time", ns).text for t in tracks]
    assert "2026-03-02T01:00:05Z" in first_times


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_only_on_a_terminal():
    from common.progress import ProgressBar

    terminal, pipe = _Terminal(), io.StringIO()
    for stream in (terminal, pipe):
        bar = ProgressBar(stream, width=10)
        bar(0.5, "shift 1")
        bar(1.0, "done")
    assert "[#####-----]  50% shift 1" in terminal.getvalue()
    assert terminal.getvalue().endswith("\n")
    assert pipe.getvalue() == ""


def test_job_mode_makes_a_queued_report(scenario, django_capture_on_commit_callbacks):
    from reports.models import Report
    from reports.services.generation import request_report

    with django_capture_on_commit_callbacks(execute=False):
        report = request_report(scenario.event, {"no_tiles": True, "name": "per job"})
    out = io.StringIO()
    call_command("ftt_report", "--job", str(report.pk), stdout=out)
    report.refresh_from_db()
    assert report.status == Report.Status.DONE
    assert f"report {report.pk}: reports/test-event-{scenario.event.pk}/" in out.getvalue()
    with pytest.raises(CommandError, match="Report 999999 does not exist"):
        call_command("ftt_report", "--job", "999999")


def test_site_logo_replaces_the_default(scenario, tmp_path, settings):
    from reports.documents.event_report import render_report
    from reports.documents.options import ReportOptions

    logo = tmp_path / "kunde.png"
    logo.write_bytes(png((120, 60), (250, 0, 250)))
    settings.FTT_REPORT_LOGO = str(logo)
    pdf = render_report(scenario.event, ReportOptions(no_tiles=True)).pdf
    path = tmp_path / "r.pdf"
    path.write_bytes(pdf)
    first_page_images = PdfReader(str(path)).pages[0].images
    assert len(first_page_images) == 1
    assert first_page_images[0].image.size == (120, 60)


@pytest.mark.parametrize("month", ["0000-01", "10000-01", "2026-13", "2026-00", "May"])
def test_a_month_beyond_the_calendar_is_refused_with_a_message(db, tmp_path, month):
    with pytest.raises(CommandError, match="between 0001-01 and 9999-12"):
        call_command("ftt_report", "--dmv", str(tmp_path / "dmv.csv"), "--month", month)
    assert not (tmp_path / "dmv.csv").exists()


@pytest.mark.parametrize("month", ["0001-01", "9999-12"])
def test_the_first_and_last_month_of_the_calendar_give_an_empty_report(test_event, tmp_path, month):
    out = tmp_path / "dmv.csv"
    call_command("ftt_report", "--dmv", str(out), "--month", month, stdout=io.StringIO())
    assert len(list(csv.reader(io.StringIO(out.read_text())))) == 1
