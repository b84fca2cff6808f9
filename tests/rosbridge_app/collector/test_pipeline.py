"""The collector's decisions, fed directly (no ROS, no database)."""

import math
from datetime import UTC, datetime, timedelta
from types import SimpleNamespace as NS

import numpy as np
import pytest

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.bag import bag_events
from rosbridge_app.collector.pipeline import Pipeline
from tests.support.fkie import FKIE_BAG, full_rate_length, gps_path_length

T0 = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)


def at(seconds):
    return T0 + timedelta(seconds=seconds)


def stamp(seconds):
    ns = int(at(seconds).timestamp() * 1e9)
    return NS(sec=ns // 10**9, nanosec=ns % 10**9)


def fix(seconds, lat, lon, status=0):
    return NS(
        header=NS(stamp=stamp(seconds)),
        status=NS(status=status),
        latitude=lat,
        longitude=lon,
        altitude=0.0,
        position_covariance=[0.0] * 9,
        position_covariance_type=0,
    )


def mode(auto: bool):
    return NS(data=auto)


def tf_msg(seconds, parent, child, x, y, yaw=0.0):
    return NS(
        transforms=[
            NS(
                header=NS(stamp=stamp(seconds), frame_id=parent),
                child_frame_id=child,
                transform=NS(
                    translation=NS(x=x, y=y, z=0.0),
                    rotation=NS(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
                ),
            )
        ]
    )


@pytest.fixture
def sink():
    return []


@pytest.fixture
def pipe(sink):
    return Pipeline(sink.append)


def kinds(events):
    return [e.kind for e in events]


def test_mode_before_logging_opens_a_segment_at_start(pipe, sink):
    pipe.on_mode(mode(True), at(0))  # an on-change publisher: said once, before logging
    assert sink == []
    pipe.start_logging(at(5))
    assert kinds(sink) == [ev.START, ev.MODE]
    assert sink[1].data["mode"] == "auto"
    pipe.on_mode(mode(True), at(6))
    assert kinds(sink) == [ev.START, ev.MODE]  # same mode: nothing new
    pipe.on_mode(mode(False), at(7))
    assert sink[-1].data["mode"] == "ito"


def test_parked_robot_adds_no_rows_and_bad_fixes_are_ignored(pipe, sink):
    pipe.start_logging(at(0))
    pipe.on_mode(mode(True), at(0))
    for i in range(100):
        pipe.on_fix(fix(i * 0.1, 50.0, 7.0), at(i * 0.1))
    pipe.on_fix(fix(11, float("nan"), 7.0), at(11))
    pipe.on_fix(fix(12, 51.0, 7.0, status=-1), at(12))
    assert kinds(sink).count(ev.GPS_FIX) == 1


def test_fixes_of_a_driver_that_leaves_the_status_unset_are_recorded_and_said_once(
    pipe, sink, caplog
):
    pipe.start_logging(at(0))
    pipe.on_mode(mode(True), at(0))
    for i in range(3):
        pipe.on_fix(fix(i, 50.0 + i * 1e-4, 7.0, status=-2), at(i))
    assert kinds(sink).count(ev.GPS_FIX) == 3
    said = [r for r in caplog.records if "NavSatStatus unset" in r.getMessage()]
    assert len(said) == 1


def test_switch_starts_the_new_segment_where_the_robot_is(pipe, sink):
    pipe.start_logging(at(0))
    pipe.on_mode(mode(False), at(0))
    pipe.on_fix(fix(0, 50.0, 7.0), at(0))
    pipe.on_fix(fix(1, 50.00001, 7.0), at(1))  # 1.1 m: recorded
    pipe.on_fix(fix(1.1, 50.000011, 7.0), at(1.1))  # 0.1 m: thinned away
    pipe.on_mode(mode(True), at(1.2))
    tail = sink[-3:]
    assert kinds(tail) == [ev.GPS_FIX, ev.MODE, ev.GPS_FIX]
    # The skipped fix ends the old segment and starts the new one.
    assert tail[0].data["lat"] == tail[2].data["lat"] == 50.000011
    assert tail[1].data["gps"] == [7.0, 50.000011]


def test_no_local_pose_without_a_complete_tf_chain(pipe, sink):
    pipe.start_logging(at(0))
    pipe.on_mode(mode(True), at(0))
    pipe.on_tf(tf_msg(0, "odom", "base_link", 5, 5), at(0))  # map→odom unknown
    assert ev.LOCAL_POSE not in kinds(sink)
    pipe.on_tf(tf_msg(0, "map", "odom", 1, 0), at(0.05))
    local = [e for e in sink if e.kind == ev.LOCAL_POSE]
    assert [(e.data["x"], e.data["y"]) for e in local] == [(6, 5)]


def test_turning_on_the_spot_is_recorded_with_yaw(pipe, sink):
    pipe.start_logging(at(0))
    pipe.on_mode(mode(True), at(0))
    pipe.on_tf(tf_msg(0, "map", "odom", 0, 0), at(0), static=True)
    for i in range(10):
        pipe.on_tf(tf_msg(i, "odom", "base_link", 1, 1, yaw=i * 0.3), at(i))
    yaws = [e.data["yaw"] for e in sink if e.kind == ev.LOCAL_POSE]
    assert len(yaws) == 10
    assert yaws[-1] == pytest.approx(2.7)


def test_images_before_a_switch_go_to_the_new_master_once(pipe, sink):
    pipe.update_params({"params.image_buffer_size": 2, "params.image_buffer_step": 1.0})
    frame = NS(
        header=NS(stamp=stamp(0)),
        encoding="rgb8",
        width=2,
        height=2,
        step=6,
        is_bigendian=False,
        data=bytes(12),
    )
    pipe.start_logging(at(0))
    pipe.on_mode(mode(True), at(0))
    for i in range(10):
        pipe.on_image(frame, at(i * 0.5))
    pipe.on_mode(mode(False), at(5))
    pipe.on_mode(mode(True), at(6))
    masters = [e for e in sink if e.kind == ev.MODE]
    images = [e.prepare() for e in sink if e.kind == ev.IMAGE]
    assert len(images) == 2  # buffer size; nothing repeated at the next switch
    assert {i.data["master"] for i in images} == {str(masters[1].uid)}
    assert all(i.blob.startswith(b"\xff\xd8") for i in images)


def test_map_is_stored_only_when_it_changes(pipe, sink):
    def grid(value):
        o = NS(position=NS(x=0.0, y=0.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))
        return NS(
            header=NS(stamp=stamp(0), frame_id="map"),
            info=NS(width=2, height=2, resolution=0.1, origin=o),
            data=np.array([value, 0, 0, 0], np.int8),
        )

    pipe.on_grid(grid(0), at(0))  # latched, before logging
    pipe.start_logging(at(1))
    pipe.on_grid(grid(0), at(10))
    pipe.on_grid(grid(100), at(20))
    maps = [e.prepare() for e in sink if e.kind == ev.MAP]
    assert len(maps) == 2
    assert maps[0].blob.startswith(b"\x89PNG")


def test_ready_made_map_picture_replaces_the_drawn_grid(pipe, sink):
    import io

    from PIL import Image as PilImage

    o = NS(position=NS(x=-1.0, y=2.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))
    grid = NS(
        header=NS(stamp=stamp(0), frame_id="map"),
        info=NS(width=8, height=4, resolution=0.5, origin=o),
        data=np.zeros(32, np.int8),
    )
    picture = io.BytesIO()
    PilImage.new("RGB", (8, 4), (20, 40, 220)).save(picture, format="JPEG")
    jpeg = NS(format="jpeg", data=picture.getvalue())
    pipe.start_logging(at(0))
    pipe.on_map_jpeg(jpeg, at(1))  # no geometry yet: nothing to store
    assert not [e for e in sink if e.kind == ev.MAP]
    pipe.on_grid(grid, at(100))
    pipe.on_map_jpeg(jpeg, at(200))
    pipe.on_map_jpeg(jpeg, at(300))  # the same picture again changes nothing
    maps = [e.prepare() for e in sink if e.kind == ev.MAP]
    assert len(maps) == 2
    drawn, pictured = (PilImage.open(io.BytesIO(m.blob)).convert("RGB") for m in maps)
    assert drawn.getpixel((0, 0)) == (254, 254, 254)  # free grid cells
    r, g, b = pictured.getpixel((4, 2))
    assert b > 180 and r < 60
    assert (maps[1].data["width"], maps[1].data["origin_x"]) == (8, -1.0)


@pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available")
def test_thinned_fkie_path_is_within_one_percent_of_full_rate():
    events = bag_events(FKIE_BAG, {"params.robot_mode_type": "industrial"})
    assert [e.data["mode"] for e in events if e.kind == ev.MODE] == [
        "ito",
        "auto",
        "ito",
        "auto",
        "ito",
    ]
    kept = thinned = 0.0
    segment = []
    for e in events + [None]:
        if e is None or e.kind == ev.MODE:
            kept += gps_path_length(segment)
            segment = []
        elif e.kind == ev.GPS_FIX:
            segment.append((e.data["lon"], e.data["lat"]))
    full = full_rate_length()
    thinned = sum(1 for e in events if e.kind == ev.GPS_FIX)
    assert abs(kept - full) / full < 0.01
    assert thinned < 1000  # from 21 722 fixes
    assert 215 < kept < 230
