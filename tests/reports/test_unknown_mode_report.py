"""Time and distance logged before the robot said its mode: one figure in the
statistics, printed in the report's data-quality section (issue 30)."""

from datetime import timedelta

import pytest

from events.services import logs, segments
from events.services.segments import GpsPosition
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from reports.selectors.statistics import event_statistics
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix
from tests.support.pdf import flat, has_row, pdf_text
from tests.support.scenario import STEP, STEP_M, T0


def at(seconds: float):
    return T0 + timedelta(seconds=seconds)


@pytest.fixture
def late_mode_event(vehicle, performer, media_root):
    """75 s and two steps east before the robot's first mode, then 60 s AUTO."""
    event = logs.create_test_event(location="late mode", at=T0)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    leg = logs.create_leg(shift=shift, at=T0)
    unknown = segments.report_mode(leg, "unknown", at=at(0), gps=GpsPosition(0.0, 0.0)).master
    pose_writes.store_poses(unknown, [GpsFix(longitude=STEP, latitude=0.0, robot_stamp=at(30))])
    auto = segments.report_mode(leg, "auto", at=at(75), gps=GpsPosition(2 * STEP, 0.0)).master
    pose_writes.store_poses(auto, [GpsFix(longitude=3 * STEP, latitude=0.0, robot_stamp=at(100))])
    logs.close_leg(leg, at=at(135))
    return event


def test_unknown_mode_counts_in_the_totals_but_not_in_autonomy(late_mode_event):
    figures = event_statistics(late_mode_event).overall
    assert (figures.unknown_seconds, figures.auto_seconds) == (75.0, 60.0)
    assert figures.unknown_distance == pytest.approx(2 * STEP_M)
    assert figures.total_distance == pytest.approx(3 * STEP_M)
    assert figures.total_seconds == 135.0
    assert figures.autonomy_ratio_distance == 1.0 and figures.autonomy_ratio_time == 1.0
    assert (figures.auto_runs, figures.ito_runs, figures.interventions) == (1, 0, 0)


def test_the_data_quality_section_gives_the_time_and_distance_without_a_known_mode(
    late_mode_event, tmp_path, settings
):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    result = render_report(late_mode_event, ReportOptions(no_tiles=True))
    raw = pdf_text(result.pdf, tmp_path)
    text = flat(raw)
    assert (
        "Logged before the robot said its mode (unknown mode; in the totals, not in autonomy "
        f"or intervention figures): 0:01:15 and {2 * STEP_M:.2f} m"
    ) in text
    assert has_row(raw, "Total distance", f"{3 * STEP_M:.2f} m")
