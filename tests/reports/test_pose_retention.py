"""The retention policy thins old shifts' poses to what the report draws; the
figures, the statistics and newer shifts stay as they were."""

import math
from datetime import UTC, datetime, timedelta

import numpy as np
import pytest
import shapely
from django.core.management import call_command

from events.models import SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from reports.charts.maps import Line, map_tolerance
from reports.documents.sections import OVERVIEW_SIZE
from reports.selectors.provenance import data_digest
from reports.selectors.statistics import event_statistics, figures
from reports.services.pose_retention import thin_old_poses
from telemetry.models import LocalPose, Pose, SegmentFigures, ThinnedSegment
from telemetry.selectors.tracks import load_tracks
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.services.segment_figures import differences
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

pytestmark = pytest.mark.django_db

NOW = datetime.now(UTC)
OLD = NOW - timedelta(days=800)
RECENT = NOW - timedelta(days=2)


def _drive(leg, start, count=600):
    """A gently curving drive of ``count`` fixes a second apart, a tenth of a
    metre of jitter on it, with local poses beside it; returns the master."""
    leg.start = start - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    master = segments.report_mode(
        leg, SegmentType.AUTO, at=start, gps=GpsPosition(8.0, 50.0)
    ).master
    fixes, local = [], []
    for i in range(count):
        wiggle = 1e-6 * math.sin(i * 1.7)
        stamp = start + timedelta(seconds=i)
        fixes.append(GpsFix(8.0 + i * 2e-5, 50.0 + 1e-3 * math.sin(i / 150) + wiggle,
                            robot_stamp=stamp))  # fmt: skip
        local.append(MapPose(x=i * 0.5, y=20 * math.sin(i / 150) + 0.01 * math.sin(i * 1.7),
                             frame="map", robot_stamp=stamp))  # fmt: skip
    pose_writes.store_poses(master, fixes)
    pose_writes.store_local_poses(master, local)
    return master


def _seen(event):
    """The event's statistics as the report prints them (runs and their sums)."""
    runs = event_statistics(event, GPS_TRACK).runs
    return [(r.id, r.distance, r.pose_count, r.start, r.end) for r in runs], figures(runs)


def _figures():
    return {(f.segment_id, f.mode): f for f in SegmentFigures.objects.all()}


def _farthest_dropped(mode, before, after) -> float:
    """How far (in the map's metres) a removed point lies from the thinned track,
    and the map's half pixel."""
    tolerance, (full, thin) = map_tolerance(
        mode, [Line(before.x, before.y, "0,0,0"), Line(after.x, after.y, "0,0,0")], OVERVIEW_SIZE
    )
    line = shapely.linestrings(np.column_stack([thin.x, thin.y]))
    points = shapely.points(np.column_stack([full.x, full.y]))
    return float(shapely.distance(line, points).max()), tolerance


def test_retention_is_off_by_default(leg):
    _drive(leg, OLD)
    count = Pose.objects.count()
    assert thin_old_poses() == 0
    assert Pose.objects.count() == count


def test_old_shifts_are_thinned_to_the_report_drawing_and_figures_stay(leg, other_leg, settings):
    old = _drive(leg, OLD)
    new = _drive(other_leg, RECENT)
    event = leg.shift.test_event
    figures, statistics, digest = _figures(), _seen(event), data_digest(event)
    tracks = {mode: load_tracks([old.pk, new.pk], mode) for mode in (GPS_TRACK, LOCAL_TRACK)}
    settings.FTT_POSE_RETENTION_MONTHS = 12

    call_command("ftt_pose_storage")

    # Figures and statistics read the stored figures: unchanged.
    after = _figures()
    assert after.keys() == figures.keys()
    for key, kept in figures.items():
        assert differences(kept, after[key]) == []
    assert _seen(event) == statistics
    # A report built before the thinning still verifies: its digest covered the
    # uids as the figures kept them.
    assert data_digest(event) == digest
    for mode, model in ((GPS_TRACK, Pose), (LOCAL_TRACK, LocalPose)):
        thinned = load_tracks([old.pk, new.pk], mode)
        # The old shift keeps few points, first and last among them, and the
        # drawing moves by less than half a pixel of its map.
        assert len(thinned[old.pk]) < len(tracks[mode][old.pk]) / 5
        assert thinned[old.pk].x[0] == tracks[mode][old.pk].x[0]
        assert thinned[old.pk].x[-1] == tracks[mode][old.pk].x[-1]
        farthest, half_pixel = _farthest_dropped(mode, tracks[mode][old.pk], thinned[old.pk])
        assert farthest <= half_pixel * 1.001
        # The newest shift is untouched.
        assert np.array_equal(thinned[new.pk].x, tracks[mode][new.pk].x)
        assert model.objects.filter(segment=new).count() == 600
    assert ThinnedSegment.objects.filter(segment=old).exists()
    assert not ThinnedSegment.objects.filter(segment=new).exists()
    # A second run finds nothing left, and a recount leaves the thinned shift.
    assert thin_old_poses() == 0
    call_command("ftt_recount_figures")
