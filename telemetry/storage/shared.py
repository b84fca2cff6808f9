"""The SQL both adapters run, given what differs (a point's constructor, the
functions of the earlier and the later of two values); each adapter module
says which it uses."""

from datetime import datetime

from django.db import connection

from events.models import PoseSource, Segment
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.storage import keys
from telemetry.storage.rows import Change, StoredFigures, floats, stored_figures_from

FIGURES = SegmentFigures._meta.db_table


def stored_figures_returning(segment_column: str, mode: str) -> str:
    """SQL of ``StoredFigures`` as scalar subqueries, for the RETURNING list of a pose
    insert (``segment_column``: its row's segment), so a single pose reads the
    figures without a statement of its own."""
    return ", ".join(
        f"(SELECT {column} FROM {FIGURES} WHERE segment_id = {segment_column} AND mode = '{mode}')"
        for column in keys.STORED_FIGURES_COLUMNS
    )


def one_pose_sql(point: str, refused: str = "") -> str:
    """One pose, one statement (``point``: the point from longitude and
    latitude in the database's spatial SQL): it stores nothing when the uid is
    known, the segment or a named pose source is gone (the master comes from a
    per-process cache) or the query ``refused`` finds a row, and returns what
    the segment's figures hold, which the pose is then added to."""
    guard = f"AND NOT EXISTS ({refused})" if refused else ""
    return f"""
INSERT INTO {Pose._meta.db_table} ({keys.POSE_COLUMNS})
SELECT %s, m.id, {point}, %s, %s, %s, %s, %s, %s
FROM {Segment._meta.db_table} m
WHERE m.id = %s
  AND (%s IS NULL OR EXISTS (SELECT 1 FROM {PoseSource._meta.db_table} WHERE id = %s))
  {guard}
ON CONFLICT DO NOTHING
RETURNING id, {stored_figures_returning(Pose._meta.db_table + ".segment_id", keys.GPS_TRACK)}
"""


def insert_pose(point: str, master_id: int, fix, source_id, received, refused_by=None):
    def prepared(name, value):
        return Pose._meta.get_field(name).get_db_prep_value(value, connection)

    params = [
        prepared("uid", fix.uid),
        *floats([fix.longitude, fix.latitude, fix.altitude]),
        int(fix.fix_status),
        *floats([fix.horizontal_accuracy]),
        source_id,
        prepared("robot_stamp", fix.robot_stamp),
        prepared("received", received),
        master_id,
        source_id,
        source_id,
    ]
    refused = ""
    if refused_by is not None:
        # The rule's own query (its home is the service that passes it), not a copy.
        refused, refused_params = refused_by.values("pk").order_by().query.sql_with_params()
        params += refused_params
    with connection.cursor() as cursor:
        cursor.execute(one_pose_sql(point, refused), params)
        row = cursor.fetchone()
    return None if row is None else (row[0], stored_figures_from(row[1:]))


# Creates the row or takes it as it is, and locks it either way (an upsert
# locks the row it meets), in one statement.
_LOCK = f"""
INSERT INTO {FIGURES} (segment_id, mode, points, no_fix, length) VALUES (%s, %s, 0, 0, 0)
ON CONFLICT (segment_id, mode) DO UPDATE SET mode = excluded.mode
RETURNING *
"""


def locked_figures(master_id: int, mode: str) -> SegmentFigures:
    return next(iter(SegmentFigures.objects.raw(_LOCK, [master_id, mode])))


def read_stored_figures(master_id: int, mode: str) -> StoredFigures | None:
    with connection.cursor() as cursor:
        cursor.execute(
            f"SELECT {', '.join(keys.STORED_FIGURES_COLUMNS)} FROM {FIGURES} "
            "WHERE segment_id = %s AND mode = %s",
            [master_id, mode],
        )
        row = cursor.fetchone()
    return None if row is None else stored_figures_from(row)


def upsert_sql(least: str, greatest: str) -> str:
    """The conditional upsert of a figures row: it applies only while the row
    holds the counts the writer read (``upsert_params``)."""

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
INSERT INTO {FIGURES} AS f (segment_id, mode, {", ".join(keys.FIGURE_FIELDS)})
VALUES (%s, %s, {", ".join(["%s"] * len(keys.FIGURE_FIELDS))})
ON CONFLICT (segment_id, mode) DO UPDATE SET
  points = f.points + excluded.points, no_fix = f.no_fix + excluded.no_fix,
  length = f.length + %s, uid_sum = %s, {", ".join(moved)},
  {extreme(least, "first_stamp")}, {extreme(greatest, "last_stamp")},
  {extreme(least, "min_x")}, {extreme(least, "min_y")},
  {extreme(greatest, "max_x")}, {extreme(greatest, "max_y")}
WHERE f.points = %s AND f.no_fix = %s
"""


def upsert_params(master_id: int, mode: str, seen: StoredFigures | None, change: Change) -> list:
    alone = adapted(change.alone[name] for name in keys.FIGURE_FIELDS)
    params = [master_id, mode, *alone, change.length, change.uid_sum]
    params += [change.first] * 2 + [change.last] * 5
    params += [None, None] if seen is None else [seen.points, seen.no_fix]
    return params


def _point_sql(mode: str) -> tuple[str, str]:
    # The points of a track as (id, x, y); GPS: usable fixes only.
    if mode == keys.GPS_TRACK:
        return f"SELECT id, ST_X(point), ST_Y(point) FROM {Pose._meta.db_table}", (
            keys.USABLE_FIX_SQL
        )
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
            params += [master_id, *adapted(values)]
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
            f"ORDER BY {keys.order_sql()}",
            [master_id, *adapted(values)],
        )
        return [tuple(row) for row in cursor.fetchall()]


def adapted(values) -> list:
    ops = connection.ops
    return [ops.adapt_datetimefield_value(v) if isinstance(v, datetime) else v for v in values]
