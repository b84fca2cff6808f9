"""The PostgreSQL adapter of the storage port.

Pose tables are partitioned by month of the robot stamp
(telemetry.services.pose_partitions); every insert skips a uid already stored
in its partition (``ON CONFLICT DO NOTHING``), so a retried pose or batch is
stored once even when two retries race.  Batches travel as binary column
arrays, big ones by COPY; tracks are read packed into bytes, one row per
segment (docs/gui.md, "Big tracks").
"""

from dataclasses import dataclass
from datetime import UTC

import numpy as np
import psycopg
from django.core.exceptions import EmptyResultSet
from django.db import connection, transaction

from events.models import Announcement
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus
from telemetry.storage import keys, shared
from telemetry.storage.rows import NewPoint, as_uuid, floats, stored_figures_from

NAME = "postgresql"
POINT = "ST_SetSRID(ST_MakePoint(%s, %s), 4326)"
# The earlier and the later of two values, NULL skipped.
LEAST, GREATEST = "LEAST", "GREATEST"


def bound_cursor(*, binary_results: bool = False):
    """A cursor on Django's connection (same transaction, logged and counted like
    Django's own) that sends its parameters apart from the SQL text.

    Django binds parameters into the text on the client, which rules out
    binary parameters (``%b``: psycopg packs a list of floats or uuids in C)
    and binary results (bytes as stored, not hex text to decode).
    """
    connection.ensure_connection()
    raw = psycopg.Cursor(connection.connection)
    if binary_results:
        raw.format = psycopg.pq.Format.BINARY
    wrap = connection.make_debug_cursor if connection.queries_logged else connection.make_cursor
    return wrap(raw)


# --- writes ------------------------------------------------------------------


def insert_pose(master_id: int, fix, source_id: int | None, received, refused_by=None):
    return shared.insert_pose(POINT, master_id, fix, source_id, received, refused_by)


def _numbered(sent: str, target: str) -> str:
    """The insert ``target`` of the rows ``sent`` gives (each numbered ``n`` by
    its place in the batch), answering with the place and the id of each new
    row in the order sent: the rest of a NewPoint is what was sent, so no uid, stamp or
    coordinate travels back.  Of a uid sent twice the first is stored, the
    smaller place.  ``target`` ends where a caller's rule may add its
    ``WHERE NOT EXISTS``."""
    return f"""
WITH sent AS ({sent}),
stored AS ({target} {{refused}} ON CONFLICT DO NOTHING RETURNING uid, id)
SELECT min(sent.n), stored.id FROM stored JOIN sent ON sent.u = stored.uid
GROUP BY stored.id ORDER BY 1
"""


# One statement with one array per column: its cost does not grow with the
# batch on the client side (no per-row SQL text, no per-row geometry object),
# and ON CONFLICT makes a concurrent retry of the same uid a no-op, not an error.
# The arrays travel as binary parameters (%b): psycopg packs a list of floats,
# uuids or datetimes in C.
_FIXES_INTO = f"""INSERT INTO {Pose._meta.db_table} ({keys.POSE_COLUMNS})
SELECT u, %b, ST_SetSRID(ST_MakePoint(x, y), 4326), a, f, h, %b, r, %b FROM sent"""
_FIXES_INSERT = _numbered(
    "SELECT * FROM unnest(%b::int4[], %b::uuid[], %b::float8[], %b::float8[], %b::float8[], "
    "%b::int2[], %b::float8[], %b::timestamptz[]) AS t(n, u, x, y, a, f, h, r)",
    _FIXES_INTO,
)

# As for fixes (a replayed outage spool is two thirds local poses).
_LOCAL_INTO = f"""INSERT INTO {LocalPose._meta.db_table} ({keys.LOCAL_POSE_COLUMNS})
SELECT u, %b, f, x, y, w, r, %b FROM sent"""
_LOCAL_INSERT = _numbered(
    "SELECT * FROM unnest(%b::int4[], %b::uuid[], %b::text[], %b::float8[], %b::float8[], "
    "%b::float8[], %b::timestamptz[]) AS t(n, u, f, x, y, w, r)",
    _LOCAL_INTO,
)


def insert_fixes(master, source_id, fixes, received, refused_by=None) -> list[NewPoint]:
    columns = (
        list(range(len(fixes))),
        [as_uuid(f.uid) for f in fixes],
        floats(f.longitude for f in fixes),
        floats(f.latitude for f in fixes),
        floats(f.altitude for f in fixes),
        [int(f.fix_status) for f in fixes],
        floats(f.horizontal_accuracy for f in fixes),
        [f.robot_stamp for f in fixes],
    )
    stored = _insert_columns(
        _POSE_STAGING, _FIXES_INSERT, columns, [master.pk, source_id, received], refused_by
    )
    return _new_points(stored, fixes, received, lambda f: (f.longitude, f.latitude,
                       f.fix_status != FixStatus.NO_FIX))  # fmt: skip


def insert_local_poses(master, poses, received) -> list[NewPoint]:
    columns = (
        list(range(len(poses))),
        [as_uuid(p.uid) for p in poses],
        [p.frame for p in poses],
        floats(p.x for p in poses),
        floats(p.y for p in poses),
        floats(p.yaw for p in poses),
        [p.robot_stamp for p in poses],
    )
    stored = _insert_columns(_LOCAL_POSE_STAGING, _LOCAL_INSERT, columns, [master.pk, received])
    return _new_points(stored, poses, received, lambda p: (p.x, p.y, True))


def _insert_columns(staging, insert: str, columns, params, refused_by=None) -> list[tuple]:
    """Store the rows given as column lists (their places first, then the
    uids, in the staging table's order) whose uid is new, unless the queryset
    ``refused_by`` finds a row; returns (place, id) of each.  ``params`` come
    after the columns in ``insert`` and are the staging insert's own
    parameters."""
    refused, refused_params = "", []
    if refused_by is not None:
        # The rule's own query (its home is the service that passes it), not a copy.
        sql, refused_params = refused_by.values("pk").order_by().query.sql_with_params()
        refused = f"WHERE NOT EXISTS ({sql})"
    if len(columns[0]) >= COPY_FROM:
        return _copy_new(staging, zip(*columns, strict=True), [*params, *refused_params], refused)
    with bound_cursor() as cursor:
        cursor.execute(insert.format(refused=refused), [*columns, *params, *refused_params])
        return cursor.fetchall()


# From this many rows on, a batch goes by COPY into a temporary table and one
# INSERT ... SELECT from there; below it the two extra round trips (the table,
# the COPY) cost more than they save.
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
    "n int4, u uuid, x float8, y float8, a float8, f int2, h float8, r timestamptz",
    ("int4", "uuid", "float8", "float8", "float8", "int2", "float8", "timestamptz"),
    _numbered("DELETE FROM ftt_pose_in RETURNING *", _FIXES_INTO.replace("%b", "%s")),
)

_LOCAL_POSE_STAGING = _Staging(
    "ftt_local_pose_in",
    "n int4, u uuid, f text, x float8, y float8, w float8, r timestamptz",
    ("int4", "uuid", "text", "float8", "float8", "float8", "timestamptz"),
    _numbered("DELETE FROM ftt_local_pose_in RETURNING *", _LOCAL_INTO.replace("%b", "%s")),
)


def _copy_new(staging: _Staging, rows, params, refused: str) -> list[tuple]:
    """Copy ``rows`` (tuples in the staging table's column order) and store those
    whose uid is new (``refused``: the caller's condition); returns their
    (place, id)."""
    with bound_cursor() as cursor:
        cursor.execute(staging.create())
        with cursor.copy(f"COPY {staging.name} FROM STDIN (FORMAT BINARY)") as copy:
            copy.set_types(staging.types)
            for row in rows:
                copy.write_row(row)
        cursor.execute(staging.insert.format(refused=refused), params)
        return cursor.fetchall()


def _new_points(stored, sent, received, position) -> list[NewPoint]:
    """NewPoints of the ``stored`` (place, id) rows from what was ``sent``;
    ``position`` gives a sent item's (x, y, usable)."""
    points = []
    for place, pk in stored:
        item = sent[place]
        x, y, usable = position(item)
        stamp = item.robot_stamp
        if stamp is not None and stamp.tzinfo is None:
            # Stored as UTC (Django's connections use UTC), so compared as UTC.
            stamp = stamp.replace(tzinfo=UTC)
        points.append(NewPoint(as_uuid(item.uid), pk, stamp, received, float(x), float(y), usable))
    return points


# The upsert and, when it does not apply, the row as it holds now: one round
# trip while the row is locked, not two.  The upsert has locked the row; a
# locking read (FOR UPDATE) returns its newest version, not the statement's
# snapshot, which is older when the upsert waited for another writer.
_UPSERT_OR_READ = f"""
WITH applied AS ({shared.upsert_sql(LEAST, GREATEST)} RETURNING 1),
held AS (
  SELECT {", ".join(keys.STORED_FIGURES_COLUMNS)} FROM {shared.FIGURES}
  WHERE segment_id = %s AND mode = %s AND NOT EXISTS (SELECT 1 FROM applied) FOR UPDATE
)
SELECT EXISTS (SELECT 1 FROM applied), held.*
FROM (VALUES (1)) AS one (x) LEFT JOIN held ON TRUE
"""


_FEED = Announcement._meta.db_table
# The same, and the change's feed row inserted when the upsert applies: the
# figures and the feed row are one statement, not two round trips.
_UPSERT_FEED_OR_READ = f"""
WITH applied AS ({shared.upsert_sql(LEAST, GREATEST)} RETURNING 1),
fed AS (
  INSERT INTO {_FEED} (kind, created, collector_id, leg_id, payload)
  SELECT %s, %s, %s, %s, %s WHERE EXISTS (SELECT 1 FROM applied) RETURNING id
),
held AS (
  SELECT {", ".join(keys.STORED_FIGURES_COLUMNS)} FROM {shared.FIGURES}
  WHERE segment_id = %s AND mode = %s AND NOT EXISTS (SELECT 1 FROM applied) FOR UPDATE
)
SELECT (SELECT id FROM fed), held.*
FROM (VALUES (1)) AS one (x) LEFT JOIN held ON TRUE
"""


def write_change(master_id, mode, seen, change, feed_row=None):
    params = shared.upsert_params(master_id, mode, seen, change)
    if feed_row is None:
        sql = _UPSERT_OR_READ
    else:
        sql = _UPSERT_FEED_OR_READ
        payload = Announcement._meta.get_field("payload")
        params += [
            feed_row.kind, feed_row.created, feed_row.collector_id, feed_row.leg_id,
            payload.get_db_prep_value(feed_row.payload, connection),
        ]  # fmt: skip
    with connection.cursor() as cursor:
        cursor.execute(sql, [*params, master_id, mode])
        applied, *now = cursor.fetchone()
    if feed_row is not None and applied is not None:
        feed_row.pk = applied
    if applied:
        return True, None
    if now[0] is not None:
        return False, stored_figures_from(now)
    # A row another writer created after this statement began.
    return False, shared.read_stored_figures(master_id, mode)


# --- reads -------------------------------------------------------------------

# A point as ST_AsBinary(point, 'NDR') gives it: little-endian WKB (byte order, type, x, y).
_WKB_POINT = np.dtype([("order", "u1"), ("type", "<u4"), ("x", "<f8"), ("y", "<f8")])
# timestamptz_send: big-endian microseconds since 2000-01-01 UTC.
_PG_STAMP = np.dtype(">i8")
_PG_EPOCH_MICROSECONDS = 946_684_800_000_000
# float8send: a big-endian double.
_PG_FLOAT = np.dtype(">f8")


def _in_span() -> str:
    """The poses whose robot stamp lies in the span ($2 and $3, its ends), and
    those that have none where $4 is true: a bound the planner prunes the
    month partitions by before the read starts, as the values are constants
    when it plans.  Unstamped poses are in the default partition, which only a
    read that may need them names (besides a span that reaches a month without
    a partition of its own)."""
    return "(robot_stamp BETWEEN $2 AND $3 OR ($4 AND robot_stamp IS NULL))"


def gps_tracks_sql() -> str:
    """The query of the GPS tracks (parameters as ``_read`` gives them: $1 the
    segment ids, $2 to $4 see ``_in_span``, $5 the stored figures' mode or
    NULL).  Where the read is bounded, the count of fixes without a position
    is the figures': such a fix may lie outside the span, its segment may have
    no pose inside."""
    no_fix = int(FixStatus.NO_FIX)
    return (
        "SELECT segment_id, points, stamps, "
        "CASE WHEN $5 IS NULL THEN counted ELSE COALESCE(kept.no_fix, 0)::bigint END "
        "FROM (SELECT segment_id, "
        f"string_agg(ST_AsBinary(point, 'NDR'), ''::bytea) FILTER (WHERE {keys.USABLE_FIX_SQL}) "
        "AS points, "
        f"string_agg(timestamptz_send(t), ''::bytea) FILTER (WHERE {keys.USABLE_FIX_SQL}) "
        "AS stamps, "
        f"count(*) FILTER (WHERE fix_status = {no_fix}) AS counted "
        "FROM (SELECT segment_id, point, fix_status, COALESCE(robot_stamp, received) AS t "
        f'FROM "{Pose._meta.db_table}" WHERE segment_id = ANY($1) AND {_in_span()} '
        f"ORDER BY segment_id, {keys.order_sql()}) AS ordered "
        "GROUP BY segment_id) AS read "
        "FULL JOIN (SELECT segment_id, no_fix "
        f'FROM "{SegmentFigures._meta.db_table}" '
        "WHERE segment_id = ANY($1) AND mode = $5 AND no_fix > 0) AS kept USING (segment_id)"
    )


def local_tracks_sql() -> str:
    """The query of the local tracks, read the way the GPS tracks are; the
    frame is that of each track's first point, found through the same index."""
    table = LocalPose._meta.db_table
    return (
        "SELECT segment_id, string_agg(float8send(x), ''::bytea), "
        "string_agg(float8send(y), ''::bytea), string_agg(timestamptz_send(t), ''::bytea), "
        f'(SELECT frame::text FROM "{table}" AS first WHERE first.segment_id = ordered.segment_id '
        f"AND {_in_span()} ORDER BY {keys.order_sql()} LIMIT 1) "
        "FROM (SELECT segment_id, x, y, COALESCE(robot_stamp, received) AS t "
        f'FROM "{table}" WHERE segment_id = ANY($1) AND {_in_span()} '
        f"ORDER BY segment_id, {keys.order_sql()}) AS ordered "
        "GROUP BY segment_id"
    )


_GPS_COLUMNS = "segment_id bigint, points bytea, stamps bytea, no_fix bigint"
_LOCAL_COLUMNS = "segment_id bigint, x bytea, y bytea, stamps bytea, frame text"


# The parameters of a read of every pose (``_read``).
_EVERY_POSE = {
    "$1": "%(ids)s::bigint[]",
    "$2": "'-infinity'::timestamptz",
    "$3": "'infinity'::timestamptz",
    "$4": "true",
    "$5": "NULL::text",
}


def _read(query: str, columns: str, segment_ids: list[int], figures_mode: str | None) -> list:
    """The rows of ``query`` (its columns as ``columns`` declares them), in
    binary (as the bytes are stored), read in one statement by
    ``ftt_read_within_kept_span`` (telemetry migration 0014): it looks up the
    span of the segments' stored figures of ``figures_mode`` and plans ``query``
    with it, JIT compiling off (it costs a plain scan more than it saves).

    The figures are written in the poses' transaction, so every pose
    committed before the look-up is inside.  A ``figures_mode`` of None reads
    every pose, for measuring the figures themselves.  The aggregate keeps
    its sorted subquery's order."""
    if figures_mode is None:
        # Every pose: nothing to look up (and the figures' migration 0007
        # measures tracks before 0014 makes the function).
        for param, value in _EVERY_POSE.items():
            query = query.replace(param, value)
        with transaction.atomic(), bound_cursor(binary_results=True) as cursor:
            cursor.execute("SET LOCAL jit = off")
            cursor.execute(query, {"ids": segment_ids})
            return cursor.fetchall()
    with bound_cursor(binary_results=True) as cursor:
        cursor.execute(
            f"SELECT * FROM ftt_read_within_kept_span(%s::text, %s::bigint[], %s::text) "
            f"AS read({columns})",
            [query, segment_ids, figures_mode],
        )
        return cursor.fetchall()


def gps_tracks_plan(segment_ids: list[int], figures_mode: str, analyze: bool = False) -> list[str]:
    """PostgreSQL's plan of the GPS tracks query as ``track_arrays`` runs it,
    which shows the partitions it reads."""
    explain = "EXPLAIN (ANALYZE, BUFFERS) " if analyze else "EXPLAIN "
    rows = _read(explain + gps_tracks_sql(), "line text", segment_ids, figures_mode)
    return [line for (line,) in rows]


def _seconds(stamps: bytes | None) -> np.ndarray:
    # The same single rounding as PostgreSQL's epoch: exact microseconds, then float.
    micro = np.frombuffer(stamps or b"", dtype=_PG_STAMP) + _PG_EPOCH_MICROSECONDS
    return micro / 1e6


def track_arrays(segment_ids: list[int], mode: str, figures_mode: str | None):
    ids = [int(pk) for pk in segment_ids]
    if mode == keys.GPS_TRACK:
        for seg, points, stamps, no_fix in _read(gps_tracks_sql(), _GPS_COLUMNS, ids, figures_mode):
            points = np.frombuffer(points or b"", dtype=_WKB_POINT)
            x, y = points["x"].astype(float), points["y"].astype(float)
            yield seg, x, y, _seconds(stamps), no_fix
        return
    for seg, x, y, stamps, frame in _read(local_tracks_sql(), _LOCAL_COLUMNS, ids, figures_mode):
        x = np.frombuffer(x, dtype=_PG_FLOAT).astype(float)
        y = np.frombuffer(y, dtype=_PG_FLOAT).astype(float)
        yield seg, x, y, _seconds(stamps), frame or ""


def plain_rows(queryset) -> list[tuple]:
    # Loaded in binary: psycopg reads a timestamp in C, where Django parses
    # its text in Python (docs/report.md has the figures).
    compiler = queryset.query.get_compiler(connection=connection)
    try:
        sql, params = compiler.as_sql()
    except EmptyResultSet:  # a filter that can match nothing (pk__in=[])
        return []
    if compiler.get_converters([column for column, _sql, _alias in compiler.select]):
        raise ValueError("plain_rows reads plain columns, not fields Django converts")
    with bound_cursor(binary_results=True) as cursor:
        cursor.execute(sql, params)
        return cursor.fetchall()


def is_partitioned(table: str) -> bool:
    with connection.cursor() as cursor:
        cursor.execute("SELECT relkind = 'p' FROM pg_class WHERE oid = %s::regclass", [table])
        return cursor.fetchone()[0]


read_stored_figures = shared.read_stored_figures
locked_figures = shared.locked_figures
neighbours = shared.neighbours
points_between = shared.points_between
