"""Tracks come back in driving order with their times, without "no fix" points.

The same expectations hold on PostGIS (read by binary COPY) and SpatiaLite
(read row by row), so both readers give identical tracks.
"""

from datetime import UTC, datetime, timedelta

import numpy as np
import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events.models import SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from telemetry.models import Pose
from telemetry.models.poses import FixStatus
from telemetry.selectors.cached_tracks import cached_tracks
from telemetry.selectors.track_drawing import drawn, fit_zoom
from telemetry.selectors.tracks import Track, load_tracks
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK
from tests.support.caches import forget_cached_tracks
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db

T0 = datetime(2026, 6, 1, 9, 0, tzinfo=UTC)


def _at(seconds):
    return T0 + timedelta(seconds=seconds)


def test_points_are_ordered_by_robot_clock_and_no_fix_points_are_counted_apart(leg):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    a1 = segments.report_mode(leg, SegmentType.AUTO, at=_at(0), gps=GpsPosition(7.0, 50.0)).master
    # Sent out of order (a late batch from the collector's queue), one without a fix.
    pose_writes.store_poses(
        a1,
        [
            GpsFix(7.003, 50.003, robot_stamp=_at(30)),
            GpsFix(7.001, 50.001, robot_stamp=_at(10)),
            GpsFix(7.5, 50.5, robot_stamp=_at(15), fix_status=FixStatus.NO_FIX),
            GpsFix(7.002, 50.002, robot_stamp=_at(20)),
        ],
    )
    i1 = segments.report_mode(leg, SegmentType.ITO, at=_at(40), gps=GpsPosition(7.004, 50.0)).master
    pose_writes.store_poses(i1, [GpsFix(7.6, 50.6, fix_status=FixStatus.NO_FIX)])
    # A pose without robot clock sorts after those with one, by arrival.
    pose_writes.store_poses(a1, [GpsFix(7.0035, 50.0035)])
    received = Pose.objects.get(segment=a1, robot_stamp=None).received

    tracks = load_tracks([a1.pk, i1.pk])

    a = tracks[a1.pk]
    assert a.x.tolist() == [7.001, 7.002, 7.003, 7.0035]
    assert a.y.tolist() == [50.001, 50.002, 50.003, 50.0035]
    expected_t = [_at(s).timestamp() for s in (10, 20, 30)] + [received.timestamp()]
    assert np.allclose(a.t, expected_t, atol=1e-3)
    assert a.no_fix == 1
    i = tracks[i1.pk]
    assert len(i) == 0 and i.no_fix == 1
    assert load_tracks([]) == {}


def test_local_points_come_in_driving_order_with_their_frame(leg):
    master = start_auto(leg)
    pose_writes.store_local_poses(
        master,
        [
            pose_writes.MapPose(3.0, 30.0, "map", robot_stamp=_at(30)),
            pose_writes.MapPose(1.0, 10.0, "map", robot_stamp=_at(10)),
            pose_writes.MapPose(2.0, 20.0, "map", robot_stamp=_at(20)),
        ],
    )
    track = load_tracks([master.pk], LOCAL_TRACK)[master.pk]
    assert track.x.tolist() == [1.0, 2.0, 3.0] and track.y.tolist() == [10.0, 20.0, 30.0]
    assert np.allclose(track.t, [_at(s).timestamp() for s in (10, 20, 30)], atol=1e-3)
    assert track.frame == "map"


# A zigzag of 1 unit every 10 points along x from 0 to 1000.
ZIG_X = np.arange(1001, dtype=float)
ZIG_Y = np.where((np.arange(1001) // 10) % 2 == 1, 1.0, 0.0)


def test_the_area_in_view_keeps_its_detail_and_the_rest_is_thinned():
    coarse_x, _ = drawn(ZIG_X, ZIG_Y, 5.0)
    assert coarse_x.tolist() == [0.0, 1000.0]
    x, y = drawn(ZIG_X, ZIG_Y, 5.0, bbox=(400.0, -1.0, 600.0, 2.0), bbox_tolerance=0.1)
    inside = (x >= 400) & (x <= 600)
    # Every corner in view: a step up or down at each multiple of 10, both ends of it.
    assert set(x[inside].tolist()) >= {float(v) for v in range(410, 600, 10)}
    assert len(x[~inside]) <= 4
    # Still one line from end to end, in order, through the area in view.
    assert x[0] == 0.0 and x[-1] == 1000.0 and np.all(np.diff(x) > 0)
    assert y[inside].max() == 1.0 and y[inside].min() == 0.0


def test_fit_zoom_is_the_zoom_a_map_of_that_size_shows_the_whole_leg_at():
    # 0.01 degrees of longitude (about 700 m at 50 N) across 700 pixels needs zoom 16.6:
    # the whole leg shows at 16; twice the pixels take one zoom more.
    track = Track(1, np.array([7.0, 7.01]), np.array([50.0, 50.0]), np.zeros(2))
    assert fit_zoom(GPS_TRACK, [track], 700, 500) == 16
    assert fit_zoom(GPS_TRACK, [track], 1400, 1000) == 17
    # 100 m of map frame in 800 pixels: 8 pixels a metre, zoom 3 (2**3).
    local = Track(1, np.array([0.0, 100.0]), np.array([0.0, 50.0]), np.zeros(2))
    assert fit_zoom(LOCAL_TRACK, [local], 800, 800) == 3
    assert fit_zoom(GPS_TRACK, [], 800, 600) is None


def _closed_segments_with_tracks(leg, count):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    masters = []
    for k in range(count):
        mode = SegmentType.AUTO if k % 2 == 0 else SegmentType.ITO
        master = segments.report_mode(leg, mode, at=_at(100 * k)).master
        pose_writes.store_poses(
            master,
            [
                GpsFix(7.0 + k * 1e-3 + i * 1e-5, 50.0, robot_stamp=_at(100 * k + i))
                for i in range(50)
            ],
        )
        pose_writes.store_local_poses(
            master,
            [
                pose_writes.MapPose(k * 100.0 + i, 0.0, "map", robot_stamp=_at(100 * k + i))
                for i in range(50)
            ],
        )
        masters.append(master)
    # The next mode report closes the last of them.
    segments.report_mode(leg, SegmentType.AUTO, at=_at(100 * count))
    return masters


def _same(a: dict, b: dict):
    assert a.keys() == b.keys()
    for seg in a:
        assert a[seg].x.tolist() == b[seg].x.tolist() and a[seg].y.tolist() == b[seg].y.tolist()
        assert a[seg].t.tolist() == b[seg].t.tolist()
        assert (a[seg].frame, a[seg].no_fix) == (b[seg].frame, b[seg].no_fix)


def test_cached_tracks_are_the_tracks_and_a_late_pose_in_a_closed_segment_shows_up(leg):
    masters = _closed_segments_with_tracks(leg, 3)
    ids = [m.pk for m in masters]
    forget_cached_tracks()
    first = cached_tracks(masters)
    with CaptureQueriesContext(connection) as unchanged:
        again = cached_tracks(masters)
    for mode in (GPS_TRACK, LOCAL_TRACK):
        _same(first[mode], load_tracks(ids, mode))
        _same(again[mode], first[mode])
    # Nothing changed: only the poses are counted, no track is read again.
    assert len(unchanged) == 1

    # A collector's spool replays a fix driven in the middle of the first segment.
    pose_writes.store_poses(masters[0], [GpsFix(7.5, 50.5, robot_stamp=_at(10.5))])
    pose_writes.store_local_poses(
        masters[0], [pose_writes.MapPose(-5.0, 1.0, "map", robot_stamp=_at(10.5))]
    )
    later = cached_tracks(masters)
    for mode in (GPS_TRACK, LOCAL_TRACK):
        _same(later[mode], load_tracks(ids, mode))
    gps, local = later[GPS_TRACK][masters[0].pk], later[LOCAL_TRACK][masters[0].pk]
    assert len(gps) == len(local) == 51
    assert gps.x[10:13].tolist() == [7.0 + 10 * 1e-5, 7.5, 7.0 + 11 * 1e-5]
    assert local.x[10:13].tolist() == [10.0, -5.0, 11.0]
