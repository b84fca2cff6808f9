"""Local (map-frame) mode: planar distances, occupancy map under the tracks."""

import io
import math
from datetime import timedelta

import numpy as np
import pytest
from PIL import Image as PILImage

from events.services import logs, segments
from events.services.segments import LocalPosition
from reports.charts.maps import Background, Line, MapPainter
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from reports.selectors.statistics import event_statistics
from telemetry.services import map_images, pose_writes
from telemetry.services.pose_writes import MapPose
from tests.support.pdf import flat, pdf_text, save_pages
from tests.support.scenario import T0


def _grid_png(width=40, height=30) -> bytes:
    buf = io.BytesIO()
    PILImage.new("L", (width, height), 230).save(buf, "PNG")
    return buf.getvalue()


@pytest.fixture
def local_event(vehicle, performer, media_root):
    """AUTO (0,0) -> (3,0) -> (3,4) -> next start (6,8): 3 + 4 + 5 = 12 m;
    ITO (6,8) -> (6,9): 1 m."""
    event = logs.create_test_event(location="Halle 3", time_zone="Europe/Berlin", at=T0)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    leg = logs.create_leg(shift=shift, at=T0)
    map_images.store_map(
        shift,
        png=_grid_png(),
        frame="map",
        width=40,
        height=30,
        resolution=0.5,
        origin_x=-5.0,
        origin_y=-5.0,
        origin_yaw=0.3,
    )

    def poses(points, start):
        return [
            MapPose(x=x, y=y, frame="map", robot_stamp=start + timedelta(seconds=10 * (i + 1)))
            for i, (x, y) in enumerate(points)
        ]

    auto = segments.report_mode(leg, "auto", at=T0, local=LocalPosition(0.0, 0.0, "map")).master
    pose_writes.store_local_poses(auto, poses([(3, 0), (3, 4)], T0))
    t1 = T0 + timedelta(seconds=60)
    ito = segments.report_mode(
        leg, "ito", at=t1, local=LocalPosition(6.0, 8.0, "map"), reason="safety"
    ).master
    pose_writes.store_local_poses(ito, poses([(6, 9)], t1))
    logs.close_leg(leg, at=T0 + timedelta(seconds=100))
    return event


def test_local_distances_are_planar_with_joins(local_event):
    overall = event_statistics(local_event, "local").overall
    assert overall.auto_distance == pytest.approx(12.0)
    assert overall.manual_distance == pytest.approx(1.0)
    # In GPS mode the same event has no positions at all.
    assert event_statistics(local_event, "gps").overall.total_distance == 0


def test_local_report_draws_the_occupancy_map(local_event, tmp_path):
    result = render_report(local_event, ReportOptions(local=True))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert "Autonomous distance 12.00 m" in text
    assert "Positions: local map frame" in text
    assert "No occupancy map recorded" not in text
    assert not result.warnings
    save_pages(result.pdf, "local-mode")


def _dark_share_left_right(path) -> tuple[float, float]:
    pixels = np.asarray(PILImage.open(path).convert("L"))
    dark = pixels < 60
    half = dark.shape[1] // 2
    return dark[:, :half].mean(), dark[:, half:].mean()


@pytest.mark.parametrize("yaw, darker", [(0.0, "right"), (math.pi / 2, "left")])
def test_occupancy_map_is_turned_by_its_yaw_about_its_origin(tmp_path, yaw, darker):
    # A black 10 x 20 m map with its origin at (0, 0): unturned it lies right of
    # x = 0; turned by 90 degrees it lies left of it.
    background = Background(np.zeros((20, 10), dtype=np.uint8), 1.0, 0.0, 0.0, yaw)
    track = [Line([-25.0, 25.0], [-25.0, 25.0], "255,255,255", width=0.1)]
    path = tmp_path / f"map-{yaw}.png"
    MapPainter().local_map(track, background, str(path), size=(4, 4))
    left, right = _dark_share_left_right(path)
    assert (right > 2 * left) if darker == "right" else (left > 2 * right)
