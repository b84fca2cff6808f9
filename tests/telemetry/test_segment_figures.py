"""Per-segment figures stored at write time equal what the distance rule gives
from the poses, whatever order, repetition or path the poses arrive by."""

import random
import threading
from datetime import UTC, datetime, timedelta

import pytest
from django.core.management import CommandError, call_command
from django.db import connection, connections
from django.db.migrations.executor import MigrationExecutor
from django.test.utils import CaptureQueriesContext

from common import uid_sums
from events.models import Segment, SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import import_bundle
from reports.selectors.statistics import event_statistics
from telemetry.models import Pose, SegmentFigures, ThinnedSegment
from telemetry.models.poses import FixStatus
from telemetry.selectors.distances import displayed_distances, measured_paths, stored_distances
from telemetry.selectors.tracks import masters
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.services.segment_figures import (
    TOLERANCE_M,
    differences,
    measure_figures,
    recount_figures,
)
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

# On SpatiaLite too: poses, figures and tracks are stored by the SQL of each database.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]

T0 = datetime(2026, 6, 1, 9, 0, tzinfo=UTC)


def _fixes(count, seed):
    """A wiggly drive of ``count`` fixes, a tenth of them without a position and
    a few without the robot's clock (they sort last)."""
    rnd = random.Random(seed)
    fixes = []
    for i in range(count):
        stamp = None if rnd.random() < 0.05 else T0 + timedelta(seconds=i)
        status = FixStatus.NO_FIX if rnd.random() < 0.1 else FixStatus.FIX
        fixes.append(
            GpsFix(8.0 + i * 1e-5 + rnd.random() * 1e-6, 50.0 + rnd.random() * 1e-5,
                   fix_status=status, robot_stamp=stamp)
        )  # fmt: skip
    return fixes


def _open_master(leg, lon=8.0):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    return segments.report_mode(leg, SegmentType.AUTO, at=T0, gps=GpsPosition(lon, 50.0)).master


def _assert_stored_equal_poses(leg):
    ids = [m.pk for m in masters(leg=leg)]
    assert recount_figures(ids) == {}
    for mode in (GPS_TRACK, LOCAL_TRACK):
        kept = stored_distances(list(masters(leg=leg)), mode)
        measured = {
            pk: p.distance for pk, p in measured_paths(list(masters(leg=leg)), mode).items()
        }
        assert kept.keys() == measured.keys()
        for pk, distance in measured.items():
            assert (kept[pk] is None) == (distance is None)
            if distance is not None:
                assert kept[pk] == pytest.approx(distance, abs=TOLERANCE_M)


@pytest.mark.parametrize("seed", [1, 2])
def test_random_orders_duplicates_and_late_batches_keep_exact_figures(leg, seed):
    rnd = random.Random(seed)
    first = _open_master(leg, 7.9999)
    fixes = _fixes(120, seed)
    live, late = fixes[:80], fixes[80:]
    # Live batches in order, each also sent again (a retry after a lost answer).
    for begin in range(0, 60, 20):
        batch = live[begin : begin + 20]
        pose_writes.store_poses(first, batch)
        pose_writes.store_poses(first, batch[:5])
    # Single poses, one of them twice, and a shuffled batch.
    for fix in live[60:70] + [live[65]]:
        pose_writes.store_pose(first.pk, fix)
    shuffled = live[70:]
    rnd.shuffle(shuffled)
    pose_writes.store_poses(first, shuffled)
    _assert_stored_equal_poses(leg)
    # The spool of an outage replayed: earlier stamps after later ones, in random batches.
    rnd.shuffle(late)
    for fix in late:
        fix.robot_stamp = fix.robot_stamp and fix.robot_stamp - timedelta(minutes=30)
    pose_writes.store_poses(first, late[:20])
    pose_writes.store_poses(first, late[20:])
    pose_writes.store_local_poses(
        first, [MapPose(x=rnd.random() * 10, y=i * 0.5, frame="map",
                        robot_stamp=T0 + timedelta(seconds=rnd.randrange(100))) for i in range(30)]
    )  # fmt: skip
    # A second master after the first: the join to its start changes the first's distance.
    segments.report_mode(leg, SegmentType.ITO, at=T0 + timedelta(minutes=5),
                         gps=GpsPosition(8.002, 50.0))  # fmt: skip
    _assert_stored_equal_poses(leg)
    kept = SegmentFigures.objects.get(segment=first, mode=GPS_TRACK)
    usable = Pose.objects.filter(segment=first).exclude(fix_status=FixStatus.NO_FIX)
    assert (
        kept.points == usable.count()
        and kept.no_fix == Pose.objects.filter(segment=first).count() - kept.points
    )
    assert displayed_distances(list(masters(leg=leg)))[first.pk] == pytest.approx(
        measured_paths(list(masters(leg=leg)), GPS_TRACK)[first.pk].distance, abs=TOLERANCE_M
    )


def test_statistics_read_figures_not_poses(leg, test_event):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(30, 3))
    with CaptureQueriesContext(connection) as queries:
        stats = event_statistics(test_event, GPS_TRACK)
    assert not [q for q in queries if Pose._meta.db_table + '"' in q["sql"]]
    run = stats.runs[0]
    assert run.distance == pytest.approx(
        measured_paths([master], GPS_TRACK)[master.pk].distance, abs=TOLERANCE_M
    )
    assert run.pose_count == SegmentFigures.objects.get(segment=master, mode=GPS_TRACK).points


def test_recount_command_reports_and_sets_right_a_difference(leg):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(10, 4))
    call_command("ftt_recount_figures")
    SegmentFigures.objects.filter(segment=master, mode=GPS_TRACK).update(length=1.0, points=3)
    with pytest.raises(CommandError):
        call_command("ftt_recount_figures")
    call_command("ftt_recount_figures", "--fix")
    assert recount_figures([master.pk]) == {}


def test_deleting_a_segment_deletes_its_figures(leg):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(5, 5))
    Segment.objects.filter(pk=master.pk).delete()
    assert not SegmentFigures.objects.filter(segment_id=master.pk).exists()


def test_import_merging_poses_into_a_track_measures_it_again(leg, tmp_path, media_root):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(40, 6))
    export_events(tmp_path / "day.zip", select_events())
    # This installation lost every other pose; the archive brings them back in between.
    Pose.objects.filter(
        segment=master,
        id__in=list(Pose.objects.filter(segment=master).values_list("id", flat=True))[::2],
    ).delete()
    measure_figures([master.pk])
    with open_archive(tmp_path / "day.zip") as bundle:
        import_bundle(bundle)
    assert Pose.objects.filter(segment=master).count() == 40
    _assert_stored_equal_poses(leg)


def _in_batches(master, share):
    for begin in range(0, len(share), 10):
        pose_writes.store_poses(master, share[begin : begin + 10])


def _one_by_one(master, share):
    for fix in share:
        pose_writes.store_pose(master.pk, fix)


@pytest.mark.postgis_only
@pytest.mark.django_db(transaction=True)
@pytest.mark.parametrize("send", [_in_batches, _one_by_one])
def test_two_writers_on_one_segment_at_once(leg, send):
    master = _open_master(leg)
    fixes = _fixes(200, 7)
    # Interleaved stamps: each writer's points fall between the other's.
    shares = [fixes[0::2], fixes[1::2]]
    barrier = threading.Barrier(2)
    errors = []

    def write(share):
        try:
            barrier.wait()
            send(master, share)
        except Exception as exc:  # noqa: BLE001 - reported by the test below
            errors.append(exc)
        finally:
            connections.close_all()

    threads = [threading.Thread(target=write, args=(s,)) for s in shares]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert Pose.objects.filter(segment=master).count() == 200
    _assert_stored_equal_poses(leg)


@pytest.mark.django_db(transaction=True)
def test_migration_measures_the_tracks_of_an_existing_database(leg):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(30, 8))
    pose_writes.store_local_poses(
        master, [MapPose(x=i, y=i * i * 0.1, frame="map") for i in range(5)]
    )
    kept = {(f.segment_id, f.mode): f for f in SegmentFigures.objects.all()}
    executor = MigrationExecutor(connection)
    executor.migrate([("telemetry", "0006_localpose_order_covering_index")])
    executor.loader.build_graph()
    executor.migrate(executor.loader.graph.leaf_nodes())
    again = {(f.segment_id, f.mode): f for f in SegmentFigures.objects.all()}
    assert again.keys() == kept.keys() == {(master.pk, GPS_TRACK), (master.pk, LOCAL_TRACK)}
    for key, figures in kept.items():
        assert differences(figures, again[key]) == []


@pytest.mark.django_db(transaction=True)
def test_migration_sums_the_uids_left_of_a_thinned_master_and_keeps_its_figures(leg):
    master = _open_master(leg)
    pose_writes.store_poses(master, _fixes(40, 9))
    ThinnedSegment.objects.create(segment=master)
    ids = list(Pose.objects.filter(segment=master).order_by("id").values_list("id", flat=True))
    Pose.objects.filter(pk__in=ids[1:30:2]).delete()
    kept = SegmentFigures.objects.get(segment=master, mode=GPS_TRACK)
    executor = MigrationExecutor(connection)
    executor.migrate([("telemetry", "0014_tracks_read_in_one_statement")])
    executor.loader.build_graph()
    executor.migrate(executor.loader.graph.leaf_nodes())
    again = SegmentFigures.objects.get(segment=master, mode=GPS_TRACK)
    left = Pose.objects.filter(segment=master).values_list("uid", flat=True)
    assert again.uid_sum == uid_sums.combined(uid_sums.uid_sum(left)) != kept.uid_sum
    assert differences(kept, again) == [f"uid_sum: {kept.uid_sum!r} != {again.uid_sum!r}"]


def test_late_single_pose_in_the_middle_of_a_long_track_reads_only_its_neighbours(leg):
    master = _open_master(leg)
    fixes = _fixes(2000, 9)
    late = fixes.pop(1000)
    late.fix_status, late.robot_stamp = FixStatus.FIX, T0 + timedelta(seconds=1000)
    pose_writes.store_poses(master, fixes)
    with CaptureQueriesContext(connection) as queries:
        pose_writes.store_pose(master.pk, late)
    # The track is not read again: one read of the pose table, of the late
    # point's two neighbours.
    reads = [
        q["sql"]
        for q in queries
        if q["sql"].startswith("SELECT") and Pose._meta.db_table in q["sql"]
    ]
    assert len(reads) == 1 and reads[0].count("LIMIT 1") >= 2
    _assert_stored_equal_poses(leg)
    kept = SegmentFigures.objects.get(segment=master, mode=GPS_TRACK)
    assert (
        kept.points
        == Pose.objects.filter(segment=master).exclude(fix_status=FixStatus.NO_FIX).count()
    )
