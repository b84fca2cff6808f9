"""Pose rows as each database stores them: the SQL that differs between
PostgreSQL and SpatiaLite lives here, one function per job, and nowhere else.

Every insert skips a uid already stored (``ON CONFLICT DO NOTHING``), so a
retried pose or batch is stored once even when two retries race.
"""

import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import NamedTuple

from django.db import connection

from common.sql import bound_cursor
from events.models import PoseSource, Segment
from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus
from telemetry.services import figure_rows


class NewPoint(NamedTuple):
    """A point an insert stored, with what its segment's figures need
    (telemetry.services.segment_figures); ``usable``: not a fix without a position."""

    uid: uuid.UUID
    id: int
    robot_stamp: datetime | None
    received: datetime
    x: float
    y: float
    usable: bool


# What an insert returns of each new row: its uid and id.  The rest of a
# NewPoint is what was sent, so no stamp or coordinate travels back.
_RETURNING = "RETURNING uid, id"


# The columns of a GPS pose row, in the order every insert below gives them.
POSE_COLUMNS = (
    "uid, segment_id, point, altitude, fix_status, horizontal_accuracy, "
    "pose_source_id, robot_stamp, received"
)

# A point from longitude and latitude, in each database's spatial SQL.
_POINT = {
    "postgresql": "ST_SetSRID(ST_MakePoint(%s, %s), 4326)",
    "sqlite": "MakePoint(%s, %s, 4326)",
}

# One pose, one statement: it stores nothing when the segment or a named pose
# source is gone (the master comes from a per-process cache), and returns what
# the segment's figures hold, which the pose is then added to.
_ONE_POSE = f"""
INSERT INTO {Pose._meta.db_table} ({POSE_COLUMNS})
SELECT %s, m.id, {{point}}, %s, %s, %s, %s, %s, %s
FROM {Segment._meta.db_table} m
WHERE m.id = %s
  AND (%s IS NULL OR EXISTS (SELECT 1 FROM {PoseSource._meta.db_table} WHERE id = %s))
ON CONFLICT DO NOTHING
RETURNING id, {figure_rows.kept_returning(Pose._meta.db_table + ".segment_id", figure_rows.GPS)}
"""


def insert_pose(
    master_id: int, fix, source_id: int | None, received
) -> tuple[int, figure_rows.Kept | None] | None:
    """Store one checked fix on the master segment ``master_id``; the new row's id
    and what its segment's figures held, or None when nothing was stored (a
    known uid, or the segment or pose source no longer exists)."""

    def prepared(name, value):
        return Pose._meta.get_field(name).get_db_prep_value(value, connection)

    params = [
        prepared("uid", fix.uid),
        *_floats([fix.longitude, fix.latitude, fix.altitude]),
        int(fix.fix_status),
        *_floats([fix.horizontal_accuracy]),
        source_id,
        prepared("robot_stamp", fix.robot_stamp),
        prepared("received", received),
        master_id,
        source_id,
        source_id,
    ]
    with connection.cursor() as cursor:
        cursor.execute(_ONE_POSE.format(point=_POINT[connection.vendor]), params)
        row = cursor.fetchone()
    return None if row is None else (row[0], figure_rows.kept_from(row[1:]))


def insert_fixes(master, source_id, fixes, received) -> list[NewPoint]:
    """Store checked fixes on ``master``; the new rows."""
    if connection.vendor == "postgresql":
        return _insert_fixes_postgres(master, fixes, source_id, received)
    rows = [fix.row(master, source_id, received) for fix in fixes]
    return [
        NewPoint(r.uid, r.pk, r.robot_stamp, r.received, r.point.x, r.point.y,
                 r.fix_status != FixStatus.NO_FIX)
        for r in insert_new(Pose, rows)
    ]  # fmt: skip


def insert_local_poses(master, poses, received) -> list[NewPoint]:
    """Store checked map-frame poses on ``master``; the new rows."""
    if connection.vendor == "postgresql":
        return _insert_local_postgres(master, poses, received)
    rows = insert_new(LocalPose, [pose.to_local_pose(master, received) for pose in poses])
    return [NewPoint(r.uid, r.pk, r.robot_stamp, r.received, r.x, r.y, True) for r in rows]


# One statement with one array per column: its cost does not grow with the
# batch on the client side (no per-row SQL text, no per-row geometry object),
# and ON CONFLICT makes a concurrent retry of the same uid a no-op, not an error.
# The arrays travel as binary parameters (%b): psycopg packs a list of floats,
# uuids or datetimes in C, about three times faster than writing each element
# as text, which was most of the client's time for a big batch.
_POSTGRES_INSERT = """
INSERT INTO {table} ({columns})
SELECT u, %b, ST_SetSRID(ST_MakePoint(x, y), 4326), a, f, h, %b, r, %b
FROM unnest(%b::uuid[], %b::float8[], %b::float8[], %b::float8[], %b::int2[],
            %b::float8[], %b::timestamptz[]) AS t(u, x, y, a, f, h, r)
ON CONFLICT DO NOTHING
{returning}
"""


def _floats(values) -> list[float | None]:
    # psycopg picks one binary type per list from its elements: a fix given as
    # whole degrees (an int) beside fractional ones must not make it an int list.
    return [None if v is None else float(v) for v in values]


def _insert_fixes_postgres(master, fixes, source_id, received) -> list[NewPoint]:
    columns = (
        [as_uuid(f.uid) for f in fixes],
        _floats(f.longitude for f in fixes),
        _floats(f.latitude for f in fixes),
        _floats(f.altitude for f in fixes),
        [int(f.fix_status) for f in fixes],
        _floats(f.horizontal_accuracy for f in fixes),
        [f.robot_stamp for f in fixes],
    )
    insert = _POSTGRES_INSERT.format(
        table=Pose._meta.db_table, columns=POSE_COLUMNS, returning=_RETURNING
    )
    stored = _insert_columns(_POSE_STAGING, insert, columns, [master.pk, source_id, received])
    return _new_points(stored, fixes, received, lambda f: (f.longitude, f.latitude,
                       f.fix_status != FixStatus.NO_FIX))  # fmt: skip


def _insert_columns(staging, insert: str, columns, params) -> list[tuple]:
    """Store the rows given as column lists (the uid's first, in the staging
    table's order) whose uid is new; returns them.  ``params`` come before
    the columns in ``insert`` and are the staging insert's own parameters."""
    if len(columns[0]) >= COPY_FROM:
        return _copy_new(staging, zip(*columns, strict=True), params)
    with bound_cursor() as cursor:
        cursor.execute(insert, [*params, *columns])
        return cursor.fetchall()


# From this many rows on, a batch goes to PostgreSQL by COPY into a temporary
# table and one INSERT ... SELECT from there: a third less time than one
# INSERT of unnested arrays for 5 000 poses, in the server (COPY parses rows
# cheaper) and in the client (psycopg writes binary rows in C).  Below it the
# two extra round trips (the table, the COPY) cost more than they save.
COPY_FROM = 100


@dataclass(frozen=True)
class _Staging:
    """A temporary table that a batch is copied into, and the statement that moves
    its rows into the real table.  The retry rule needs ON CONFLICT, which COPY
    lacks; the statement empties the table, so a batch after another in the same
    transaction (an importer's) finds it empty, and ON COMMIT DELETE ROWS gives
    the space back (autovacuum never visits temporary tables)."""

    name: str
    columns: str
    types: tuple[str, ...]
    insert: str

    def create(self) -> str:
        # Per database session; a rolled-back transaction takes it along, so it
        # is asked for every time (one cheap round trip per batch).
        return (
            f"CREATE TEMPORARY TABLE IF NOT EXISTS {self.name} ({self.columns}) "
            "ON COMMIT DELETE ROWS"
        )


_POSE_STAGING = _Staging(
    "ftt_pose_in",
    "u uuid, x float8, y float8, a float8, f int2, h float8, r timestamptz",
    ("uuid", "float8", "float8", "float8", "int2", "float8", "timestamptz"),
    f"""
WITH moved AS (DELETE FROM ftt_pose_in RETURNING *)
INSERT INTO {Pose._meta.db_table} ({POSE_COLUMNS})
SELECT u, %s, ST_SetSRID(ST_MakePoint(x, y), 4326), a, f, h, %s, r, %s FROM moved
ON CONFLICT DO NOTHING
{_RETURNING}
""",
)

_LOCAL_POSE_STAGING = _Staging(
    "ftt_local_pose_in",
    "u uuid, frame text, x float8, y float8, yaw float8, r timestamptz",
    ("uuid", "text", "float8", "float8", "float8", "timestamptz"),
    f"""
WITH moved AS (DELETE FROM ftt_local_pose_in RETURNING *)
INSERT INTO {LocalPose._meta.db_table} (uid, segment_id, frame, x, y, yaw, robot_stamp, received)
SELECT u, %s, frame, x, y, yaw, r, %s FROM moved
ON CONFLICT DO NOTHING
{_RETURNING}
""",
)


def _copy_new(staging: _Staging, rows, params) -> list[tuple]:
    """Copy ``rows`` (tuples in the staging table's column order) and store those
    whose uid is new; returns their (uid, id)."""
    with bound_cursor() as cursor:
        cursor.execute(staging.create())
        with cursor.copy(f"COPY {staging.name} FROM STDIN (FORMAT BINARY)") as copy:
            copy.set_types(staging.types)
            for row in rows:
                copy.write_row(row)
        cursor.execute(staging.insert, params)
        return cursor.fetchall()


def _new_points(stored, sent, received, position) -> list[NewPoint]:
    """NewPoints of the ``stored`` (uid, id) rows from what was ``sent``;
    ``position`` gives a sent item's (x, y, usable)."""
    by_uid = {}
    for item in sent:
        # The first of a uid sent twice in one batch is the one stored.
        by_uid.setdefault(as_uuid(item.uid), item)
    points = []
    for uid, pk in stored:
        uid = as_uuid(uid)
        item = by_uid[uid]
        x, y, usable = position(item)
        stamp = item.robot_stamp
        if stamp is not None and stamp.tzinfo is None:
            # Stored as UTC (Django's connections use UTC), so compared as UTC.
            stamp = stamp.replace(tzinfo=UTC)
        point = NewPoint(uid, pk, stamp, received, float(x), float(y), usable)
        points.append(point)
    return points


def as_uuid(value) -> uuid.UUID:
    # psycopg 3 returns UUID objects, psycopg2 strings.
    return value if isinstance(value, uuid.UUID) else uuid.UUID(value)


# As for fixes: one statement of column arrays instead of a known-uid query and
# an ORM bulk insert (a replayed outage spool is two thirds local poses).
_POSTGRES_LOCAL_INSERT = """
INSERT INTO {table} (uid, segment_id, frame, x, y, yaw, robot_stamp, received)
SELECT u, %b, f, x, y, w, r, %b
FROM unnest(%b::uuid[], %b::text[], %b::float8[], %b::float8[], %b::float8[],
            %b::timestamptz[]) AS t(u, f, x, y, w, r)
ON CONFLICT DO NOTHING
{returning}
"""


def _insert_local_postgres(master, poses, received) -> list[NewPoint]:
    for pose in poses:
        pose.check()
    uids = [as_uuid(p.uid) for p in poses]
    columns = (
        uids,
        [p.frame for p in poses],
        _floats(p.x for p in poses),
        _floats(p.y for p in poses),
        _floats(p.yaw for p in poses),
        [p.robot_stamp for p in poses],
    )
    insert = _POSTGRES_LOCAL_INSERT.format(table=LocalPose._meta.db_table, returning=_RETURNING)
    stored = _insert_columns(_LOCAL_POSE_STAGING, insert, columns, [master.pk, received])
    return _new_points(stored, poses, received, lambda p: (p.x, p.y, True))


def insert_new(model, rows) -> list:
    """The rows whose uid is not stored yet, inserted (with their ids set)."""
    if not rows:
        return []
    known = set(model.objects.filter(uid__in=[r.uid for r in rows]).values_list("uid", flat=True))
    fresh = [r for r in rows if r.uid not in known]
    model.objects.bulk_create(fresh, batch_size=1000)
    return fresh
