"""The storage port's contract: what each operation does, stated once for both
adapters (telemetry.storage.postgresql and .spatialite).  Each case runs with
the adapter of the database under test, so the SpatiaLite pass runs the
SpatiaLite adapter's."""

import uuid
from datetime import UTC, datetime, timedelta

import pytest
from django.db import connection
from django.utils import timezone

from events.models import Segment, SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from telemetry import storage
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus
from telemetry.services import pose_partitions, pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.storage import keys, postgresql
from telemetry.storage.rows import Change

pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]

T0 = datetime(2026, 6, 1, 9, 0, tzinfo=UTC)


def _at(seconds):
    return T0 + timedelta(seconds=seconds)


@pytest.fixture(params=sorted(storage.ADAPTERS))
def adapter(request):
    if connection.vendor != request.param:
        pytest.skip(f"the {request.param} adapter runs on its own database")
    assert storage.adapter() is storage.ADAPTERS[request.param]
    return storage.ADAPTERS[request.param]


@pytest.fixture
def master(leg):
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    return segments.report_mode(leg, SegmentType.AUTO, at=T0, gps=GpsPosition(7.0, 50.0)).master


def _fixes(n, start=0, **kwargs):
    return [GpsFix(7.0 + i * 1e-4, 50.0, robot_stamp=_at(start + i), **kwargs) for i in range(n)]


def test_one_pose_is_stored_once_and_answers_what_the_figures_held(adapter, master):
    fix = GpsFix(7.1, 50.1, robot_stamp=_at(1))
    pk, kept = adapter.insert_pose(master.pk, fix, None, timezone.now())
    assert kept is None  # no figures row yet
    assert Pose.objects.get(pk=pk).uid == fix.uid
    assert adapter.insert_pose(master.pk, fix, None, timezone.now()) is None
    assert Pose.objects.filter(uid=fix.uid).count() == 1


def test_one_pose_for_a_gone_segment_or_pose_source_stores_nothing(adapter, master):
    fix = GpsFix(7.1, 50.1)
    assert adapter.insert_pose(master.pk + 1000, fix, None, timezone.now()) is None
    assert adapter.insert_pose(master.pk, fix, 987654, timezone.now()) is None
    assert not Pose.objects.filter(uid=fix.uid).exists()


@pytest.mark.parametrize("size", [3, postgresql.COPY_FROM + 5], ids=["small", "big"])
def test_a_batch_stores_each_new_uid_once(adapter, master, size):
    fixes = _fixes(size)
    fixes[1] = GpsFix(9.0, 51.0, fix_status=FixStatus.NO_FIX, uid=fixes[1].uid)
    # A uid sent twice in one batch: the first copy is stored.
    twice = GpsFix(8.0, 50.5, uid=fixes[0].uid)
    received = timezone.now()
    new = adapter.insert_fixes(master, None, [*fixes, twice], received)
    assert sorted(p.uid for p in new) == sorted(f.uid for f in fixes)
    by_uid = {p.uid: p for p in new}
    assert by_uid[fixes[0].uid].x == pytest.approx(7.0)
    assert not by_uid[fixes[1].uid].usable and by_uid[fixes[2].uid].usable
    assert {p.id for p in new} == set(
        Pose.objects.filter(segment=master).values_list("pk", flat=True)
    )
    # Retried with one more: only that one is new.
    more = GpsFix(7.9, 50.9)
    again = adapter.insert_fixes(master, None, [*fixes, more], timezone.now())
    assert [p.uid for p in again] == [more.uid]
    assert Pose.objects.filter(segment=master).count() == size + 1


@pytest.mark.parametrize("size", [2, postgresql.COPY_FROM], ids=["small", "big"])
def test_a_batch_keeps_every_value_as_sent_including_the_missing_ones(
    adapter, master, pose_source, size
):
    sent = [
        GpsFix(7, 50, altitude=-1.5, fix_status=FixStatus.GBAS, horizontal_accuracy=0.02,
               robot_stamp=_at(1)),
        GpsFix(7.25, 50.5),
        *_fixes(size - 2, start=10),
    ]  # fmt: skip
    received = _at(99)
    adapter.insert_fixes(master, pose_source.pk, sent, received)
    stored = {p.uid: p for p in Pose.objects.filter(segment=master)}
    for fix in sent:
        row = stored[fix.uid]
        assert (row.point.x, row.point.y) == (fix.longitude, fix.latitude)
        assert (row.altitude, row.fix_status, row.horizontal_accuracy) == (
            fix.altitude, fix.fix_status, fix.horizontal_accuracy
        )  # fmt: skip
        assert (row.robot_stamp, row.received, row.pose_source_id) == (
            fix.robot_stamp, received, pose_source.pk
        )  # fmt: skip


@pytest.mark.parametrize("size", [2, postgresql.COPY_FROM], ids=["small", "big"])
def test_a_batch_of_local_poses_stores_each_new_uid_once(adapter, master, size):
    poses = [MapPose(float(i), -1.0, "map", yaw=0.5, robot_stamp=_at(i)) for i in range(size)]
    new = adapter.insert_local_poses(master, [*poses, MapPose(5.0, 5.0, "map", uid=poses[0].uid)],
                                     timezone.now())  # fmt: skip
    assert sorted(p.uid for p in new) == sorted(p.uid for p in poses)
    assert LocalPose.objects.get(uid=poses[0].uid).x == 0.0
    assert adapter.insert_local_poses(master, poses, timezone.now()) == []


def test_tracks_come_in_driving_order_unstamped_last_and_no_fixes_counted(adapter, master):
    late = [GpsFix(7.003, 50.0, robot_stamp=_at(30)), GpsFix(7.001, 50.0, robot_stamp=_at(10))]
    adapter.insert_fixes(master, None, [GpsFix(7.004, 50.0)], _at(100))  # no robot clock
    adapter.insert_fixes(master, None, late, _at(101))
    adapter.insert_fixes(master, None, [GpsFix(7.0, 50.0, fix_status=FixStatus.NO_FIX)], _at(102))
    adapter.insert_fixes(master, None, [GpsFix(7.002, 50.0, robot_stamp=_at(20))], _at(103))
    [(seg, x, y, t, no_fix)] = adapter.track_arrays([master.pk], keys.GPS_TRACK, None)
    assert seg == master.pk
    assert x.tolist() == [7.001, 7.002, 7.003, 7.004]
    # Seconds to the millisecond (SQLite's julianday is no finer).
    assert t.tolist() == pytest.approx([_at(s).timestamp() for s in (10, 20, 30, 100)], abs=1e-3)
    assert no_fix == 1
    # The ORM's form of the same order.
    ordered = Pose.objects.filter(keys.USABLE_FIX, segment=master).order_by(*keys.order_by())
    assert [p.point.x for p in ordered] == x.tolist()


def test_local_tracks_carry_their_first_points_frame(adapter, master):
    adapter.insert_local_poses(master, [MapPose(2.0, 0.0, "late", robot_stamp=_at(2))], _at(5))
    adapter.insert_local_poses(master, [MapPose(1.0, 0.0, "first", robot_stamp=_at(1))], _at(6))
    [(_seg, x, _y, _t, frame)] = adapter.track_arrays([master.pk], keys.LOCAL_TRACK, None)
    assert x.tolist() == [1.0, 2.0]
    assert frame == "first"


def test_a_track_read_within_the_kept_span_reads_every_stored_point(adapter, master):
    pose_writes.store_poses(master, [*_fixes(3), GpsFix(7.5, 50.0)])
    bounded = list(adapter.track_arrays([master.pk], keys.GPS_TRACK, keys.GPS_TRACK))
    every = list(adapter.track_arrays([master.pk], keys.GPS_TRACK, None))
    assert [a[1].tolist() for a in bounded] == [a[1].tolist() for a in every]
    assert len(every[0][1]) == 4


def _change(points, uid_sum="1"):
    alone = dict.fromkeys(keys.FIGURE_FIELDS)
    alone.update(points=points, no_fix=0, length=10.0, uid_sum=uid_sum, last_id=points)
    alone.update(last_x=1.0, last_y=2.0, min_x=0.5, max_x=1.0, min_y=1.5, max_y=2.0)
    return Change(alone, 10.0, points == 1, True, uid_sum)


def test_the_figures_upsert_applies_only_while_the_row_holds_what_was_read(adapter, master):
    mode = keys.GPS_TRACK
    assert adapter.read_stored_figures(master.pk, mode) is None
    assert adapter.write_change(master.pk, mode, None, _change(1)) == (True, None)
    seen = adapter.read_stored_figures(master.pk, mode)
    assert (seen.points, seen.last_x, seen.last_id) == (1, 1.0, 1)
    # A writer that read before the row was made finds what it holds now.
    applied, now = adapter.write_change(master.pk, mode, None, _change(2))
    assert not applied and now == seen
    assert adapter.write_change(master.pk, mode, seen, _change(2, "3")) == (True, None)
    row = SegmentFigures.objects.get(segment=master, mode=mode)
    assert (row.points, row.length, row.uid_sum, row.min_x, row.max_x) == (3, 20.0, "3", 0.5, 1.0)
    stale, now = adapter.write_change(master.pk, mode, seen, _change(1))
    assert not stale and now.points == 3


def test_neighbours_and_points_between_follow_driving_order(adapter, master):
    stamped = adapter.insert_fixes(master, None, _fixes(4), _at(50))
    [unstamped] = adapter.insert_fixes(master, None, [GpsFix(8.0, 50.0)], _at(60))
    adapter.insert_fixes(master, None, [GpsFix(9.0, 50.0, fix_status=FixStatus.NO_FIX)], _at(61))

    def key(p):
        return (p.robot_stamp, p.received, p.id)

    before, after = adapter.neighbours(master.pk, keys.GPS_TRACK, key(stamped[1]), key(stamped[2]))
    assert before[0] == stamped[0].id and after[0] == stamped[3].id
    before, after = adapter.neighbours(master.pk, keys.GPS_TRACK, key(stamped[3]), key(stamped[3]))
    assert before[0] == stamped[2].id and after[0] == unstamped.id
    _before, after = adapter.neighbours(master.pk, keys.GPS_TRACK, key(unstamped), key(unstamped))
    assert after is None
    between = adapter.points_between(master.pk, keys.GPS_TRACK, key(stamped[2]), key(unstamped))
    assert [p[0] for p in between] == [stamped[2].id, stamped[3].id, unstamped.id]


def test_pose_tables_are_partitioned_on_postgresql_only(adapter, master):
    partitioned = adapter is postgresql
    assert all(adapter.is_partitioned(t) == partitioned for t in pose_partitions.TABLES)
    made = pose_partitions.ensure_partitions(T0, T0 + timedelta(days=400))
    assert bool(made) == partitioned


def test_plain_rows_are_the_rows_django_reads(adapter, master):
    rows = Segment.objects.filter(pk=master.pk).values_list("id", "start", "end", "parent")
    assert adapter.plain_rows(rows) == list(rows)
    assert adapter.plain_rows(rows.filter(pk__in=[])) == []


def test_a_masters_queryset_holds_the_segments_without_a_parent(master):
    child = Segment.objects.create(
        leg=master.leg, parent=master, segment_type_id="ito", ito_reason_id="safety", start=_at(1)
    )
    assert list(Segment.objects.masters()) == [master]
    assert list(master.leg.segments.children()) == [child]
    assert uuid.UUID(str(master.uid))


def test_the_locked_figures_row_is_made_empty_or_taken_as_it_is(adapter, master):
    made = adapter.locked_figures(master.pk, keys.LOCAL_TRACK)
    assert (made.segment_id, made.mode, made.points, made.length) == (
        master.pk,
        keys.LOCAL_TRACK,
        0,
        0,
    )
    SegmentFigures.objects.filter(pk=made.pk).update(points=7)
    assert adapter.locked_figures(master.pk, keys.LOCAL_TRACK).points == 7
    assert SegmentFigures.objects.filter(segment=master, mode=keys.LOCAL_TRACK).count() == 1
