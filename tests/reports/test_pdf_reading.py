"""What a reader copies from the PDF report works as copied (pdftotext)."""

import re

import pytest

from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from reports.selectors.provenance import data_digest
from reports.selectors.statistics import event_statistics
from telemetry.models.poses import FixStatus
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix
from tests.support.pdf import flat, pdf_text

NO_FIX = FixStatus.NO_FIX


@pytest.fixture
def text(scenario, tmp_path):
    pdf = render_report(scenario.event, ReportOptions(no_tiles=True, level="summary")).pdf
    return pdf_text(pdf, tmp_path, layout=False)


def test_the_printed_verify_command_and_digest_can_be_copied(scenario, text):
    assert "manage.py ftt_report --verify REPORT.pdf" in text
    assert "\u2013verify" not in text and "\u2014verify" not in text
    assert "\u200b" not in text
    assert data_digest(scenario.event) in text


def test_the_pose_count_of_a_segment_says_how_many_fixes_without_a_position_it_leaves_out(
    scenario, tmp_path
):
    master = scenario.masters["A2"]
    without = [GpsFix(longitude=0.0055 + i / 1e4, latitude=0.0, fix_status=NO_FIX) for i in (0, 1)]
    assert pose_writes.store_poses(master, without) == 2
    pdf = render_report(scenario.event, ReportOptions(no_tiles=True, level="full")).pdf
    text = flat(pdf_text(pdf, tmp_path))
    rows = re.findall(
        r"Poses (\d+) with a position, (\d+) without a fix \(left out\) Database id (\d+)", text
    )
    counted = {int(pk): (int(kept), int(left_out)) for kept, left_out, pk in rows}
    assert set(counted) == {m.pk for m in scenario.masters.values()}
    kept = event_statistics(scenario.event).runs
    assert {pk: n for pk, (n, _) in counted.items()} == {r.id: r.pose_count for r in kept}
    assert {pk: left_out for pk, (_, left_out) in counted.items() if left_out} == {master.pk: 2}
    assert "Positions without a GPS fix (left out): 2" in text


def test_every_page_with_times_names_their_zone_and_writes_them_all_in_it(scenario, tmp_path):
    pdf = render_report(scenario.event, ReportOptions(no_tiles=True, level="full")).pdf
    pages = pdf_text(pdf, tmp_path).split("\f")
    with_times = [page for page in pages if re.search(r"\d\d:\d\d", page)]
    assert len(with_times) > 1
    for page in with_times:
        assert "Asia/Tokyo" in page, page[:300]
    # No time is written as a UTC stamp (20260504T090000.000000Z, ...T09:00:00Z).
    text = "\f".join(pages)
    assert not re.search(r"\d{8}T\d{6}|T\d\d:\d\d:\d\d(\.\d+)?Z", text)
