"""Tracks come back in driving order with their times, without "no fix" points.

The same expectations hold on PostGIS (read by binary COPY) and SpatiaLite
(read row by row), so both readers give identical tracks.
"""

from datetime import UTC, datetime, timedelta

import numpy as np
import pytest

from events.models import SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from telemetry.models import Pose
from telemetry.models.poses import FixStatus
from telemetry.selectors.tracks import load_tracks
from telemetry.services import recording
from telemetry.services.recording import GpsFix

pytestmark = pytest.mark.django_db

T0 = datetime(2026, 6, 1, 9, 0, tzinfo=UTC)


def _at(seconds):
    return T0 + timedelta(seconds=seconds)


def test_points_are_ordered_by_robot_clock_and_no_fix_points_are_counted_apart(leg):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    a1 = segments.report_mode(leg, SegmentType.AUTO, at=_at(0), gps=GpsPosition(7.0, 50.0)).master
    # Sent out of order (a late batch from the collector's queue), one without a fix.
    recording.record_poses(
        a1,
        [
            GpsFix(7.003, 50.003, robot_stamp=_at(30)),
            GpsFix(7.001, 50.001, robot_stamp=_at(10)),
            GpsFix(7.5, 50.5, robot_stamp=_at(15), fix_status=FixStatus.NO_FIX),
            GpsFix(7.002, 50.002, robot_stamp=_at(20)),
        ],
    )
    i1 = segments.report_mode(leg, SegmentType.ITO, at=_at(40), gps=GpsPosition(7.004, 50.0)).master
    recording.record_poses(i1, [GpsFix(7.6, 50.6, fix_status=FixStatus.NO_FIX)])
    # A pose without robot clock sorts after those with one, by arrival.
    recording.record_poses(a1, [GpsFix(7.0035, 50.0035)])
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
