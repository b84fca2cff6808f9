"""The SpatiaLite adapter of the storage port.

One table per kind of pose, no partitions.  A single pose is stored by the
same statement as on PostgreSQL (``ON CONFLICT DO NOTHING``); a batch is the
rows whose uid is not stored yet, found by one query and inserted by the ORM
(an insert returning its ids skips no conflict on SQLite).  That look-up
cannot race another writer: the connection begins every transaction
IMMEDIATE (ftt_site.settings), so a writer holds the database's write lock
from its look-up to its commit.
"""

import numpy as np
from django.db import connection
from django.db.models import F, FloatField, Func
from django.db.models.functions import Coalesce

from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus
from telemetry.storage import keys, shared
from telemetry.storage.rows import NewPoint

NAME = "sqlite"
POINT = "MakePoint(%s, %s, 4326)"
# The earlier and the later of two values: SQLite's two-argument min and max
# return NULL for a NULL argument, which the upsert's COALESCE rules out.
LEAST, GREATEST = "MIN", "MAX"

_UPSERT = shared.upsert_sql(LEAST, GREATEST) + "RETURNING 1"


def insert_pose(master_id: int, fix, source_id: int | None, received, refused_by=None):
    return shared.insert_pose(POINT, master_id, fix, source_id, received, refused_by)


def insert_fixes(master, source_id, fixes, received, refused_by=None) -> list[NewPoint]:
    if refused_by is not None and refused_by.exists():
        return []
    rows = [fix.row(master, source_id, received) for fix in fixes]
    return [
        NewPoint(r.uid, r.pk, r.robot_stamp, r.received, r.point.x, r.point.y,
                 r.fix_status != FixStatus.NO_FIX)
        for r in _insert_new(Pose, rows)
    ]  # fmt: skip


def insert_local_poses(master, poses, received) -> list[NewPoint]:
    rows = _insert_new(LocalPose, [pose.to_local_pose(master, received) for pose in poses])
    return [NewPoint(r.uid, r.pk, r.robot_stamp, r.received, r.x, r.y, True) for r in rows]


def _insert_new(model, rows) -> list:
    """The rows whose uid is not stored yet, inserted (with their ids set); of
    a uid given twice, the first."""
    if not rows:
        return []
    known = set(model.objects.filter(uid__in=[r.uid for r in rows]).values_list("uid", flat=True))
    fresh = []
    for row in rows:
        if row.uid not in known:
            known.add(row.uid)
            fresh.append(row)
    model.objects.bulk_create(fresh, batch_size=1000)
    return fresh


def write_change(master_id, mode, seen, change, feed_row=None):
    # SQLite has no insert inside a WITH: the caller saves ``feed_row``.
    with connection.cursor() as cursor:
        cursor.execute(_UPSERT, shared.upsert_params(master_id, mode, seen, change))
        if cursor.fetchone() is not None:
            return True, None
    return False, shared.read_stored_figures(master_id, mode)


class _Epoch(Func):
    """Seconds since 1970 as a float, computed in the database (Django stores
    UTC text timestamps, julianday() reads them): converting 200 000
    timestamps to datetimes in Python would take most of the time."""

    output_field = FloatField()
    template = "((julianday(%(expressions)s) - 2440587.5) * 86400.0)"


class _Coordinate(Func):
    output_field = FloatField()


def _rows(segment_ids, mode):
    model = Pose if mode == keys.GPS_TRACK else LocalPose
    qs = model.objects.filter(segment_id__in=segment_ids).annotate(
        _t=_Epoch(Coalesce("robot_stamp", "received"))
    )
    if mode == keys.GPS_TRACK:
        qs = qs.annotate(
            _x=_Coordinate("point", function="ST_X"), _y=_Coordinate("point", function="ST_Y")
        )
        columns = ("segment_id", "_x", "_y", "_t", "fix_status")
    else:
        qs = qs.annotate(_x=F("x"), _y=F("y"))
        columns = ("segment_id", "_x", "_y", "_t", "frame")
    ordered = qs.order_by("segment_id", *keys.order_by())
    return ordered.values_list(*columns).iterator(chunk_size=20000)


def track_arrays(segment_ids, mode: str, figures_mode: str | None):
    # One table: every read is of every pose, ``figures_mode`` bounds nothing.
    buckets: dict[int, tuple[list, list, list, list]] = {}
    no_fix: dict[int, int] = {}
    for seg, x, y, t, extra in _rows(list(segment_ids), mode):
        if mode == keys.GPS_TRACK and extra == FixStatus.NO_FIX:
            no_fix[seg] = no_fix.get(seg, 0) + 1
            continue
        bucket = buckets.setdefault(seg, ([], [], [], []))
        bucket[0].append(x)
        bucket[1].append(y)
        bucket[2].append(t)
        if mode == keys.LOCAL_TRACK and not bucket[3]:
            bucket[3].append(extra)
    for seg, (xs, ys, ts, frame) in buckets.items():
        x, y, t = (np.asarray(v, dtype=float) for v in (xs, ys, ts))
        yield seg, x, y, t, (no_fix.pop(seg, 0) if mode == keys.GPS_TRACK else (frame or [""])[0])
    for seg, count in no_fix.items():
        yield seg, np.empty(0), np.empty(0), np.empty(0), count


def plain_rows(queryset) -> list[tuple]:
    return list(queryset)


def is_partitioned(table: str) -> bool:
    return False


read_stored_figures = shared.read_stored_figures
locked_figures = shared.locked_figures
neighbours = shared.neighbours
points_between = shared.points_between
