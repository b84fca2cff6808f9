"""The pose tables partitioned by month on PostgreSQL (one table on SpatiaLite):
the same poses and figures either way, a re-sent pose stored once, and the
migration of a database with poses reversible."""

import re
from datetime import UTC, datetime, timedelta

import pytest
from django.core.management import call_command
from django.db import connection
from django.db.migrations.executor import MigrationExecutor

from events.models import SegmentType, TestEvent
from events.services import segments
from events.services.segments import GpsPosition
from reports.selectors.statistics import event_statistics, figures
from telemetry import storage
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus
from telemetry.selectors.tracks import load_tracks
from telemetry.services import pose_partitions, pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.services.segment_figures import differences, recount_figures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK
from telemetry.storage.postgresql import gps_tracks_plan

pytestmark = pytest.mark.django_db

# The end of a month, so one segment's poses fall into two partitions.
T0 = datetime(2026, 5, 31, 23, 58, tzinfo=UTC)


def _master(leg):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    return segments.report_mode(leg, SegmentType.AUTO, at=T0, gps=GpsPosition(8.0, 50.0)).master


def _drive(master, count=240):
    """Fixes a second apart across midnight of a month's end, a few without the
    robot's clock, and local poses beside them."""
    fixes = [
        GpsFix(8.0 + i * 1e-5, 50.0 + (i % 7) * 1e-6,
               robot_stamp=None if i % 50 == 0 else T0 + timedelta(seconds=i))
        for i in range(count)
    ]  # fmt: skip
    pose_writes.store_poses(master, fixes)
    pose_writes.store_local_poses(
        master,
        [MapPose(x=i, y=i * 0.5, frame="map", robot_stamp=T0 + timedelta(seconds=i))
         for i in range(count // 2)],
    )  # fmt: skip
    return fixes


def _state(event, *, uid_sum=True):
    """What a user sees of the stored poses: counts, ids, figures, statistics
    (``uid_sum=False``: a schema from before the figures kept one)."""
    rows = SegmentFigures.objects.all() if uid_sum else SegmentFigures.objects.defer("uid_sum")
    kept = {(f.segment_id, f.mode): f for f in rows}
    runs = event_statistics(event, GPS_TRACK).runs
    return (
        sorted(Pose.objects.values_list("id", "uid", "robot_stamp")),
        sorted(LocalPose.objects.values_list("id", "uid", "x")),
        kept,
        [(r.id, r.distance, r.pose_count, r.start, r.end) for r in runs],
        figures(runs),
    )


def _assert_same(before, after, *, uid_sum=True):
    assert after[0] == before[0] and after[1] == before[1]
    assert after[2].keys() == before[2].keys()
    for key, kept in before[2].items():
        if uid_sum:
            assert differences(kept, after[2][key]) == []
        else:
            names = [f.attname for f in SegmentFigures._meta.concrete_fields if f.name != "uid_sum"]
            assert [getattr(after[2][key], n) for n in names] == [getattr(kept, n) for n in names]
    assert after[3:] == before[3:]


def _partition_of(model, uid) -> str:
    with connection.cursor() as cursor:
        table = model._meta.db_table
        cursor.execute(f"SELECT tableoid::regclass::text FROM {table} WHERE uid = %s", [uid])
        return cursor.fetchone()[0]


@pytest.mark.django_db(transaction=True)
def test_migration_back_and_forth_keeps_every_pose_and_figure(leg):
    master = _master(leg)
    _drive(master)
    event = TestEvent.objects.get(pk=leg.shift.test_event_id)
    before = _state(event)
    postgres = connection.vendor == "postgresql"
    assert all(storage.is_partitioned(t) == postgres for t in pose_partitions.TABLES)

    executor = MigrationExecutor(connection)
    executor.migrate([("telemetry", "0012_thinned_segments")])
    assert not any(storage.is_partitioned(t) for t in pose_partitions.TABLES)
    _assert_same(before, _state(event, uid_sum=False), uid_sum=False)

    executor.loader.build_graph()
    executor.migrate(executor.loader.graph.leaf_nodes())
    assert all(storage.is_partitioned(t) == postgres for t in pose_partitions.TABLES)
    _assert_same(before, _state(event))
    assert recount_figures([master.pk]) == {}
    # New poses go on with new ids after the moved ones.
    more = pose_writes.store_poses(master, [GpsFix(8.1, 50.0, robot_stamp=T0)])
    assert more == 1 and Pose.objects.order_by("id").last().id > before[0][-1][0]


def test_a_resent_pose_is_stored_once_on_every_write_path(leg):
    master = _master(leg)
    fixes = _drive(master)
    count = Pose.objects.count()
    # The batch again: small batches (one statement) and big ones (COPY).
    assert pose_writes.store_poses(master, fixes[:10]) == 0
    assert pose_writes.store_poses(master, fixes) == 0
    _, created = pose_writes.store_pose(master.pk, fixes[5])
    assert not created
    assert Pose.objects.count() == count
    assert recount_figures([master.pk]) == {}


def test_a_uid_reused_with_another_stamp_of_its_month_is_ignored(leg):
    master = _master(leg)
    fixes = _drive(master)
    count = Pose.objects.count()
    reused = GpsFix(9.0, 51.0, robot_stamp=fixes[1].robot_stamp + timedelta(seconds=5),
                    uid=fixes[1].uid)  # fmt: skip
    assert pose_writes.store_poses(master, [reused]) == 0
    row, created = pose_writes.store_pose(master.pk, reused)
    assert not created and row.point.x == pytest.approx(fixes[1].longitude)
    assert Pose.objects.count() == count
    assert recount_figures([master.pk]) == {}


@pytest.mark.postgis_only
def test_a_uid_reused_in_another_month_is_a_second_pose(leg):
    # The one case partitioning changes (pose_partitions says why): it is a
    # different pose, and the figures count it like any other.
    later = T0 + timedelta(days=40)
    pose_partitions.ensure_partitions(T0, later)
    master = _master(leg)
    fixes = _drive(master)
    count = Pose.objects.count()
    reused = GpsFix(8.01, 50.0, robot_stamp=later, uid=fixes[1].uid)
    assert pose_writes.store_poses(master, [reused]) == 1
    assert Pose.objects.count() == count + 1
    assert recount_figures([master.pk]) == {}


@pytest.mark.postgis_only
def test_the_daily_job_makes_partitions_and_moves_months_out_of_the_default(leg):
    master = _master(leg)
    fixes = _drive(master)
    default = f"{Pose._meta.db_table}_default"
    # May and June 2026 had no partition: their poses wait in the default one.
    assert _partition_of(Pose, fixes[1].uid) == default
    event = TestEvent.objects.get(pk=leg.shift.test_event_id)
    before = _state(event)

    call_command("ftt_pose_storage")

    may, june = datetime(2026, 5, 1, tzinfo=UTC), datetime(2026, 6, 1, tzinfo=UTC)
    assert _partition_of(Pose, fixes[1].uid) == pose_partitions.partition_name(
        "telemetry_pose", may
    )
    assert _partition_of(Pose, fixes[201].uid) == pose_partitions.partition_name(
        "telemetry_pose", june
    )
    # Without a robot stamp a pose stays in the default partition.
    assert _partition_of(Pose, fixes[50].uid) == default
    _assert_same(before, _state(event))
    # The coming months are there before their poses.
    now = datetime.now(UTC)
    months = pose_partitions.months_between(now, now + timedelta(days=40))
    with connection.cursor() as cursor:
        for month in months:
            name = pose_partitions.partition_name(LocalPose._meta.db_table, month)
            cursor.execute("SELECT to_regclass(%s) IS NOT NULL", [name])
            assert cursor.fetchone()[0], name
    # A second run has nothing left to do.
    assert pose_partitions.ensure_partitions() == []


def test_deleting_a_test_event_deletes_its_poses(leg):
    master = _master(leg)
    _drive(master)
    TestEvent.objects.get(pk=leg.shift.test_event_id).delete()
    assert not Pose.objects.exists() and not LocalPose.objects.exists()


def _as_read(track):
    return (track.x.tolist(), track.y.tolist(), track.t.tolist(), track.frame, track.no_fix)


def _drive_with_blind_fixes(leg, *, every_fix_stamped=False):
    """A track across a month's end (with a few points without the robot's
    clock, or none) and local poses, fixes without a position months before
    and hours after it and one unstamped, and a second master with such a fix only."""
    pose_partitions.ensure_partitions(datetime(2026, 1, 1, tzinfo=UTC), T0 + timedelta(days=1))
    master = _master(leg)
    if every_fix_stamped:
        stamps = [T0 + timedelta(seconds=i) for i in range(240)]
        pose_writes.store_poses(
            master, [GpsFix(8.0 + i * 1e-5, 50.0, robot_stamp=t) for i, t in enumerate(stamps)]
        )
        pose_writes.store_local_poses(
            master,
            [MapPose(x=i, y=0.0, frame="map", robot_stamp=t) for i, t in enumerate(stamps[:120])],
        )
    else:
        _drive(master)
    no_fix = [
        GpsFix(8.0, 50.0, fix_status=FixStatus.NO_FIX, robot_stamp=stamp)
        for stamp in (datetime(2026, 2, 3, tzinfo=UTC), None, T0 + timedelta(hours=1))
    ]
    pose_writes.store_poses(master, no_fix)
    blind = segments.report_mode(
        leg, SegmentType.ITO, at=T0 + timedelta(hours=2), gps=GpsPosition(8.1, 50.0)
    ).master
    pose_writes.store_poses(blind, [GpsFix(8.1, 50.0, fix_status=FixStatus.NO_FIX)])
    return master, blind


@pytest.mark.parametrize("every_fix_stamped", [False, True])
def test_tracks_read_within_the_kept_span_are_those_of_every_pose(leg, every_fix_stamped):
    """The drawing read, bounded by the stored figures' span, gives the tracks of
    every pose: poses without the robot's clock, fixes without a position
    outside the span, and a master with such fixes only included."""
    master, blind = _drive_with_blind_fixes(leg, every_fix_stamped=every_fix_stamped)
    ids = [master.pk, blind.pk]
    for mode in (GPS_TRACK, LOCAL_TRACK):
        bounded = load_tracks(ids, mode)
        every = load_tracks(ids, mode, within_stored_span=False)
        assert bounded.keys() == every.keys()
        for pk, track in every.items():
            assert _as_read(bounded[pk]) == _as_read(track)
    gps, local = load_tracks(ids, GPS_TRACK), load_tracks(ids, LOCAL_TRACK)
    assert (len(gps[master.pk]), gps[master.pk].no_fix) == (240, 3)
    assert (len(gps[blind.pk]), gps[blind.pk].no_fix) == (0, 1)
    assert local.keys() == {master.pk} and len(local[master.pk]) == 120


@pytest.mark.postgis_only
@pytest.mark.parametrize("every_fix_stamped", [False, True])
def test_a_track_read_reads_the_months_its_kept_span_covers(leg, every_fix_stamped):
    master, blind = _drive_with_blind_fixes(leg, every_fix_stamped=every_fix_stamped)
    assert len(load_tracks([master.pk])[master.pk]) == 240
    plan = "\n".join(gps_tracks_plan([master.pk, blind.pk], GPS_TRACK))
    table = Pose._meta.db_table
    # Not February, where a fix without a position lies, nor the months
    # before; the default partition (poses without the robot's clock) only
    # where a usable fix has no stamp, not for the unstamped fix without a
    # position.  (Unstamped fixes end the span at their arrival, today.)
    read = set(re.findall(rf" on ({table}_(?:\d{{6}}|default))\b", plan))
    months = {f"{table}_202605", f"{table}_202606"}
    assert months <= read and not {f"{table}_202601", f"{table}_202602"} & read, plan
    assert (f"{table}_default" in read) is not every_fix_stamped, plan
    assert read == months or not every_fix_stamped, plan
