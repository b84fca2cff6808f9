"""A segment's kept figures row (telemetry.models.SegmentFigures) and the track
points around new ones, as each database reads and writes them: the SQL that
differs between PostgreSQL and SpatiaLite lives here, one function per job.

Writers do not lock the row before they measure.  They read what it holds
(``Kept``), measure their change from that, and write it with one upsert that
applies only while the row still holds what they read (``write_change``);
otherwise that upsert has locked the row and, on PostgreSQL in the same
statement, read what it holds now, and they measure again from that.
"""

from dataclasses import dataclass
from datetime import UTC, datetime

from django.db import connection
from django.utils.dateparse import parse_datetime

from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus

GPS = "gps"

_TABLE = SegmentFigures._meta.db_table


@dataclass(frozen=True)
class Kept:
    """What a writer reads of the figures row: the pose set's version (its
    counts) and the last usable point, the one an appended batch joins."""

    points: int
    no_fix: int
    last_robot_stamp: datetime | None
    last_received: datetime | None
    last_id: int | None
    last_x: float | None
    last_y: float | None
    uid_sum: str


_KEPT_COLUMNS = (
    "points", "no_fix", "last_robot_stamp", "last_received", "last_id", "last_x", "last_y",
    "uid_sum",
)  # fmt: skip


def kept_returning(segment_column: str, mode: str) -> str:
    """SQL of ``Kept`` as scalar subqueries, for the RETURNING list of a pose
    insert (``segment_column``: its row's segment), so a single pose reads the
    figures without a statement of its own."""
    return ", ".join(
        f"(SELECT {column} FROM {_TABLE} WHERE segment_id = {segment_column} AND mode = '{mode}')"
        for column in _KEPT_COLUMNS
    )


def kept_from(values) -> Kept | None:
    """``Kept`` from the values of ``kept_returning`` or ``read_kept``; None
    when the segment has no figures row yet."""
    if values[0] is None:
        return None
    points, no_fix, robot_stamp, received, last_id, x, y, uids = values
    return Kept(points, no_fix, _instant(robot_stamp), _instant(received), last_id, x, y, uids)


def _instant(value) -> datetime | None:
    # SpatiaLite gives a subquery's timestamp as Django's naive UTC text.
    if isinstance(value, str):
        value = parse_datetime(value)
    if value is not None and value.tzinfo is None:
        value = value.replace(tzinfo=UTC)
    return value


def read_kept(master_id: int, mode: str) -> Kept | None:
    with connection.cursor() as cursor:
        cursor.execute(
            f"SELECT {', '.join(_KEPT_COLUMNS)} FROM {_TABLE} WHERE segment_id = %s AND mode = %s",
            [master_id, mode],
        )
        row = cursor.fetchone()
    return None if row is None else kept_from(row)


@dataclass(frozen=True)
class Change:
    """What new points change in a segment's figures.  ``alone`` are the
    figures of the new points by themselves (the row of a segment without one);
    ``length`` is what they add to the kept length; ``first``/``last`` say
    whether they become the track's first or last point; ``uid_sum`` is the
    kept uid sum with theirs added."""

    alone: dict
    length: float
    first: bool
    last: bool
    uid_sum: str


# The earlier and the later of two values either of which may be missing (SQL's
# LEAST and GREATEST skip NULL on PostgreSQL, SQLite's min and max return it).
_EXTREMES = {"postgresql": ("LEAST", "GREATEST"), "sqlite": ("MIN", "MAX")}

FIELDS = (
    "points", "no_fix", "length", "first_x", "first_y", "last_x", "last_y", "last_robot_stamp",
    "last_received", "last_id", "first_stamp", "last_stamp", "min_x", "min_y", "max_x", "max_y",
    "uid_sum",
)  # fmt: skip


def _upsert_sql() -> str:
    least, greatest = _EXTREMES[connection.vendor]

    def extreme(function, name):
        return (
            f"{name} = {function}(COALESCE(f.{name}, excluded.{name}), "
            f"COALESCE(excluded.{name}, f.{name}))"
        )

    moved = [f"{n} = CASE WHEN %s THEN excluded.{n} ELSE f.{n} END" for n in ("first_x", "first_y")]
    moved += [
        f"{n} = CASE WHEN %s THEN excluded.{n} ELSE f.{n} END"
        for n in ("last_x", "last_y", "last_robot_stamp", "last_received", "last_id")
    ]
    return f"""
INSERT INTO {_TABLE} AS f (segment_id, mode, {", ".join(FIELDS)})
VALUES (%s, %s, {", ".join(["%s"] * len(FIELDS))})
ON CONFLICT (segment_id, mode) DO UPDATE SET
  points = f.points + excluded.points, no_fix = f.no_fix + excluded.no_fix,
  length = f.length + %s, uid_sum = %s, {", ".join(moved)},
  {extreme(least, "first_stamp")}, {extreme(greatest, "last_stamp")},
  {extreme(least, "min_x")}, {extreme(least, "min_y")},
  {extreme(greatest, "max_x")}, {extreme(greatest, "max_y")}
WHERE f.points = %s AND f.no_fix = %s
"""


def write_change(
    master_id: int, mode: str, seen: Kept | None, change: Change
) -> tuple[bool, Kept | None]:
    """Add ``change`` to the figures row if it still holds ``seen`` (or, for
    None, does not exist yet): (True, None) when it did, else (False, what the
    row holds now).  When it did not, the row is locked until the transaction
    ends (an upsert locks the row it finds), so what it holds now is what the
    next ``write_change`` finds."""
    ops = connection.ops
    alone = {
        name: ops.adapt_datetimefield_value(value) if isinstance(value, datetime) else value
        for name, value in change.alone.items()
    }
    params = [master_id, mode, *(alone[name] for name in FIELDS), change.length, change.uid_sum]
    params += [change.first] * 2 + [change.last] * 5
    params += [None, None] if seen is None else [seen.points, seen.no_fix]
    with connection.cursor() as cursor:
        if connection.vendor == "postgresql":
            cursor.execute(_UPSERT_OR_READ.format(upsert=_upsert_sql()), [*params, master_id, mode])
            applied, *now = cursor.fetchone()
            if applied:
                return True, None
            if now[0] is not None:
                return False, kept_from(now)
        else:
            cursor.execute(_upsert_sql() + "RETURNING 1", params)
            if cursor.fetchone() is not None:
                return True, None
    # SQLite, or a row another writer created after this statement began.
    return False, read_kept(master_id, mode)


# The upsert and, when it does not apply, the row as it holds now: one round
# trip while the row is locked, not two.  The upsert has locked the row; a
# locking read (FOR UPDATE) returns its newest version, not the statement's
# snapshot, which is older when the upsert waited for another writer.
_UPSERT_OR_READ = f"""
WITH applied AS ({{upsert}} RETURNING 1),
held AS (
  SELECT {", ".join(_KEPT_COLUMNS)} FROM {_TABLE}
  WHERE segment_id = %s AND mode = %s AND NOT EXISTS (SELECT 1 FROM applied) FOR UPDATE
)
SELECT EXISTS (SELECT 1 FROM applied), held.*
FROM (VALUES (1)) AS one (x) LEFT JOIN held ON TRUE
"""


# The points of a track, in driving order (telemetry.selectors.driving_order),
# as (id, x, y); GPS: usable fixes only.
def _point_sql(mode: str) -> tuple[str, str]:
    if mode == GPS:
        usable = f"fix_status <> {int(FixStatus.NO_FIX)}"
        return f"SELECT id, ST_X(point), ST_Y(point) FROM {Pose._meta.db_table}", usable
    return f"SELECT id, x, y FROM {LocalPose._meta.db_table}", "TRUE"


def _parts(key: tuple, after: bool) -> list[tuple[str, list]]:
    """Conditions for the points after (or before) ``key`` (robot stamp, arrival,
    id) in driving order, nearest part first: each part has one kind of robot
    stamp, so its points are one range of the driving-order index."""
    robot_stamp, received, pk = key
    sign = ">" if after else "<"
    nulls = ("robot_stamp IS NULL AND (received, id) " + sign + " (%s, %s)", [received, pk])
    if robot_stamp is None:
        return [nulls] if after else [nulls, ("robot_stamp IS NOT NULL", [])]
    stamped = (
        "robot_stamp IS NOT NULL AND (robot_stamp, received, id) " + sign + " (%s, %s, %s)",
        [robot_stamp, received, pk],
    )
    return [stamped, ("robot_stamp IS NULL", [])] if after else [stamped]


def neighbours(master_id: int, mode: str, first: tuple, last: tuple) -> tuple:
    """(the point before ``first``, the point after ``last``) in driving order,
    each (id, x, y) or None, found through the driving-order index."""
    select, usable = _point_sql(mode)
    queries, params = [], []
    for side, key, after in ((0, first, False), (1, last, True)):
        order = "" if after else " DESC"
        for rank, (condition, values) in enumerate(_parts(key, after)):
            queries.append(
                f"SELECT * FROM (SELECT {side}, {rank}, q.* FROM ({select} "
                f"WHERE segment_id = %s AND {usable} AND {condition} "
                f"ORDER BY robot_stamp{order}, received{order}, id{order} LIMIT 1) AS q)"
                f" AS p{len(queries)}"
            )
            params += [master_id, *_adapted(values)]
    with connection.cursor() as cursor:
        cursor.execute(" UNION ALL ".join(queries), params)
        found = sorted(cursor.fetchall())
    before = next((tuple(r[2:]) for r in found if r[0] == 0), None)
    after = next((tuple(r[2:]) for r in found if r[0] == 1), None)
    return before, after


def points_between(master_id: int, mode: str, first: tuple, last: tuple) -> list[tuple]:
    """The points from ``first`` to ``last`` (both included) in driving order."""
    select, usable = _point_sql(mode)
    (stamp_a, received_a, id_a), (stamp_b, received_b, id_b) = first, last
    if stamp_a is not None and stamp_b is not None:
        condition = (
            "robot_stamp IS NOT NULL AND (robot_stamp, received, id) >= (%s, %s, %s) "
            "AND (robot_stamp, received, id) <= (%s, %s, %s)"
        )
        values = [stamp_a, received_a, id_a, stamp_b, received_b, id_b]
    elif stamp_a is not None:
        condition = (
            "(robot_stamp IS NOT NULL AND (robot_stamp, received, id) >= (%s, %s, %s)) "
            "OR (robot_stamp IS NULL AND (received, id) <= (%s, %s))"
        )
        values = [stamp_a, received_a, id_a, received_b, id_b]
    else:
        condition = (
            "robot_stamp IS NULL AND (received, id) >= (%s, %s) AND (received, id) <= (%s, %s)"
        )
        values = [received_a, id_a, received_b, id_b]
    with connection.cursor() as cursor:
        cursor.execute(
            f"{select} WHERE segment_id = %s AND {usable} AND ({condition}) "
            "ORDER BY robot_stamp IS NULL, robot_stamp, received, id",
            [master_id, *_adapted(values)],
        )
        return [tuple(row) for row in cursor.fetchall()]


def _adapted(values: list) -> list:
    ops = connection.ops
    return [ops.adapt_datetimefield_value(v) if isinstance(v, datetime) else v for v in values]
