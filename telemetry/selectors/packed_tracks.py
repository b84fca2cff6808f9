"""PostgreSQL's read of tracks: one row per segment, its points packed into bytes.

A million points cross the wire as 1 000 rows that numpy reads without a
Python object per point.  docs/gui.md ("Big tracks") explains the query's shape.
"""

import numpy as np
from django.db import connection, transaction

from common.sql import bound_cursor
from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus
from telemetry.selectors.driving_order import order_sql

# A point as ST_AsBinary(point, 'NDR') gives it: little-endian WKB (byte order, type, x, y).
_WKB_POINT = np.dtype([("order", "u1"), ("type", "<u4"), ("x", "<f8"), ("y", "<f8")])
# timestamptz_send: big-endian microseconds since 2000-01-01 UTC.
_PG_STAMP = np.dtype(">i8")
_PG_EPOCH_MICROSECONDS = 946_684_800_000_000
# float8send: a big-endian double.
_PG_FLOAT = np.dtype(">f8")


def gps_tracks_sql() -> str:
    """The query of the GPS tracks (one parameter: the segment ids), so the
    benchmark can show its plan."""
    no_fix = int(FixStatus.NO_FIX)
    return (
        "SELECT segment_id, "
        f"string_agg(ST_AsBinary(point, 'NDR'), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"string_agg(timestamptz_send(t), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"count(*) FILTER (WHERE fix_status = {no_fix}) "
        "FROM (SELECT segment_id, point, fix_status, COALESCE(robot_stamp, received) AS t "
        f'FROM "{Pose._meta.db_table}" WHERE segment_id = ANY(%s::bigint[]) '
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
        "GROUP BY segment_id"
    )


def local_tracks_sql() -> str:
    """The query of the local tracks, read the way the GPS tracks are; the
    frame is that of each track's first point, found through the same index."""
    table = LocalPose._meta.db_table
    return (
        "SELECT segment_id, string_agg(float8send(x), ''::bytea), "
        "string_agg(float8send(y), ''::bytea), string_agg(timestamptz_send(t), ''::bytea), "
        f'(SELECT frame FROM "{table}" AS first WHERE first.segment_id = ordered.segment_id '
        f"ORDER BY {order_sql()} LIMIT 1) "
        "FROM (SELECT segment_id, x, y, COALESCE(robot_stamp, received) AS t "
        f'FROM "{table}" WHERE segment_id = ANY(%s::bigint[]) '
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
        "GROUP BY segment_id"
    )


def _packed_rows(query: str, segment_ids: list[int]) -> list[tuple]:
    """The rows of ``query``, in binary (as the bytes are stored).  The aggregate
    keeps its sorted subquery's order; JIT compiling is off for the statement,
    as it costs a plain scan more than it saves (``SET LOCAL``: until the end
    of the caller's transaction where there is one)."""
    with transaction.atomic():
        with connection.cursor() as cursor:
            cursor.execute("SET LOCAL jit = off")
        with bound_cursor(binary_results=True) as cursor:
            cursor.execute(query, [segment_ids])
            return cursor.fetchall()


def _seconds(stamps: bytes | None) -> np.ndarray:
    # The same single rounding as PostgreSQL's epoch: exact microseconds, then float.
    micro = np.frombuffer(stamps or b"", dtype=_PG_STAMP) + _PG_EPOCH_MICROSECONDS
    return micro / 1e6


def gps_arrays(segment_ids: list[int]):
    """(segment id, longitudes, latitudes, seconds since 1970, fixes without a
    position) of each segment that has poses, in driving order."""
    for seg, points, stamps, no_fix in _packed_rows(gps_tracks_sql(), segment_ids):
        points = np.frombuffer(points or b"", dtype=_WKB_POINT)
        yield seg, points["x"].astype(float), points["y"].astype(float), _seconds(stamps), no_fix


def local_arrays(segment_ids: list[int]):
    """(segment id, x, y, seconds since 1970, frame) of each segment that has
    local poses, in driving order."""
    for seg, x, y, stamps, frame in _packed_rows(local_tracks_sql(), segment_ids):
        x = np.frombuffer(x, dtype=_PG_FLOAT).astype(float)
        y = np.frombuffer(y, dtype=_PG_FLOAT).astype(float)
        yield seg, x, y, _seconds(stamps), frame or ""
