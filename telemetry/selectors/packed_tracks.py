"""PostgreSQL's read of tracks: one row per segment, its points packed into bytes.

A million points cross the wire as 1 000 rows that numpy reads without a
Python object per point.  docs/gui.md ("Big tracks") explains the query's shape.
"""

import numpy as np
from django.db import transaction

from common.sql import bound_cursor
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus
from telemetry.selectors.driving_order import order_sql

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
    month partitions by (telemetry.services.pose_partitions) before the read
    starts, as the values are constants when it plans.  Unstamped poses are in
    the default partition, which only a read that may need them names
    (besides a span that reaches a month without a partition of its own)."""
    return "(robot_stamp BETWEEN $2 AND $3 OR ($4 AND robot_stamp IS NULL))"


def gps_tracks_sql() -> str:
    """The query of the GPS tracks (parameters as ``_read`` gives them: $1 the
    segment ids, $2 to $4 see ``_in_span``, $5 the kept figures' mode or
    NULL), so the benchmark can show its plan.  Where the read is bounded,
    the count of fixes without a position is the figures': such a fix may
    lie outside the span, its segment may have no pose inside."""
    no_fix = int(FixStatus.NO_FIX)
    return (
        "SELECT segment_id, points, stamps, "
        "CASE WHEN $5 IS NULL THEN counted ELSE COALESCE(kept.no_fix, 0)::bigint END "
        "FROM (SELECT segment_id, "
        f"string_agg(ST_AsBinary(point, 'NDR'), ''::bytea) FILTER (WHERE fix_status <> {no_fix}) "
        "AS points, "
        f"string_agg(timestamptz_send(t), ''::bytea) FILTER (WHERE fix_status <> {no_fix}) "
        "AS stamps, "
        f"count(*) FILTER (WHERE fix_status = {no_fix}) AS counted "
        "FROM (SELECT segment_id, point, fix_status, COALESCE(robot_stamp, received) AS t "
        f'FROM "{Pose._meta.db_table}" WHERE segment_id = ANY($1) AND {_in_span()} '
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
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
        f"AND {_in_span()} ORDER BY {order_sql()} LIMIT 1) "
        "FROM (SELECT segment_id, x, y, COALESCE(robot_stamp, received) AS t "
        f'FROM "{table}" WHERE segment_id = ANY($1) AND {_in_span()} '
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
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


def _read(query: str, columns: str, segment_ids: list[int], kept_mode: str | None) -> list:
    """The rows of ``query`` (its columns as ``columns`` declares them), in
    binary (as the bytes are stored), read in one statement by
    ``ftt_read_within_kept_span`` (telemetry migration 0014): it looks up the
    span of the segments' kept figures of ``kept_mode`` and plans ``query``
    with it, JIT compiling off (it costs a plain scan more than it saves).

    The figures are written in the poses' transaction, so every pose
    committed before the look-up is inside.  A ``kept_mode`` of None reads
    every pose, for measuring the figures themselves.  The aggregate keeps
    its sorted subquery's order."""
    if kept_mode is None:
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
            [query, segment_ids, kept_mode],
        )
        return cursor.fetchall()


def gps_tracks_plan(segment_ids: list[int], kept_mode: str, analyze: bool = False) -> list[str]:
    """PostgreSQL's plan of the GPS tracks query as ``gps_arrays`` runs it, for
    the benchmark and the tests to show which partitions it reads."""
    explain = "EXPLAIN (ANALYZE, BUFFERS) " if analyze else "EXPLAIN "
    rows = _read(explain + gps_tracks_sql(), "line text", segment_ids, kept_mode)
    return [line for (line,) in rows]


def _seconds(stamps: bytes | None) -> np.ndarray:
    # The same single rounding as PostgreSQL's epoch: exact microseconds, then float.
    micro = np.frombuffer(stamps or b"", dtype=_PG_STAMP) + _PG_EPOCH_MICROSECONDS
    return micro / 1e6


def gps_arrays(segment_ids: list[int], kept_mode: str | None):
    """(segment id, longitudes, latitudes, seconds since 1970, fixes without a
    position) of each segment that has poses, in driving order (``kept_mode``:
    see ``_read``)."""
    rows = _read(gps_tracks_sql(), _GPS_COLUMNS, segment_ids, kept_mode)
    for seg, points, stamps, no_fix in rows:
        points = np.frombuffer(points or b"", dtype=_WKB_POINT)
        yield seg, points["x"].astype(float), points["y"].astype(float), _seconds(stamps), no_fix


def local_arrays(segment_ids: list[int], kept_mode: str | None):
    """(segment id, x, y, seconds since 1970, frame) of each segment that has
    local poses, in driving order (``kept_mode``: see ``_read``)."""
    rows = _read(local_tracks_sql(), _LOCAL_COLUMNS, segment_ids, kept_mode)
    for seg, x, y, stamps, frame in rows:
        x = np.frombuffer(x, dtype=_PG_FLOAT).astype(float)
        y = np.frombuffer(y, dtype=_PG_FLOAT).astype(float)
        yield seg, x, y, _seconds(stamps), frame or ""
