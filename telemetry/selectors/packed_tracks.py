"""PostgreSQL's read of tracks: one row per segment, its points packed into bytes.

A million points cross the wire as 1 000 rows that numpy reads without a
Python object per point.  docs/gui.md ("Big tracks") explains the query's shape.
"""

from datetime import UTC, datetime

import numpy as np
from django.db import connection, transaction

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


def _in_span(unstamped: bool) -> str:
    """The poses whose robot stamp lies in a span (its two ends are
    parameters), and those that have none where ``unstamped``: a bound the
    planner prunes the month partitions by (telemetry.services.pose_partitions)
    before the read starts.  Unstamped poses are in the default partition,
    which only a read that may need them names (besides a span that reaches a
    month without a partition of its own)."""
    stamped = "robot_stamp BETWEEN %(first)s::timestamptz AND %(last)s::timestamptz"
    return f"({stamped} OR robot_stamp IS NULL)" if unstamped else f"({stamped})"


def gps_tracks_sql(unstamped: bool = True) -> str:
    """The query of the GPS tracks (parameters: ``ids``, the segment ids, and
    ``first`` and ``last``, the span's ends; ``unstamped``: see ``_in_span``),
    so the benchmark can show its plan."""
    no_fix = int(FixStatus.NO_FIX)
    return (
        "SELECT segment_id, "
        f"string_agg(ST_AsBinary(point, 'NDR'), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"string_agg(timestamptz_send(t), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"count(*) FILTER (WHERE fix_status = {no_fix}) "
        "FROM (SELECT segment_id, point, fix_status, COALESCE(robot_stamp, received) AS t "
        f'FROM "{Pose._meta.db_table}" WHERE segment_id = ANY(%(ids)s::bigint[]) '
        f"AND {_in_span(unstamped)} "
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
        "GROUP BY segment_id"
    )


def local_tracks_sql(unstamped: bool = True) -> str:
    """The query of the local tracks, read the way the GPS tracks are; the
    frame is that of each track's first point, found through the same index."""
    table = LocalPose._meta.db_table
    return (
        "SELECT segment_id, string_agg(float8send(x), ''::bytea), "
        "string_agg(float8send(y), ''::bytea), string_agg(timestamptz_send(t), ''::bytea), "
        f'(SELECT frame FROM "{table}" AS first WHERE first.segment_id = ordered.segment_id '
        f"AND {_in_span(unstamped)} ORDER BY {order_sql()} LIMIT 1) "
        "FROM (SELECT segment_id, x, y, COALESCE(robot_stamp, received) AS t "
        f'FROM "{table}" WHERE segment_id = ANY(%(ids)s::bigint[]) '
        f"AND {_in_span(unstamped)} "
        f"ORDER BY segment_id, {order_sql()}) AS ordered "
        "GROUP BY segment_id"
    )


# A span that holds every stamp: the read of every pose.
_ALL_TIME = {"first": datetime(1, 1, 1, tzinfo=UTC), "last": datetime(9999, 12, 31, tzinfo=UTC)}


def _kept_span_sql() -> str:
    """The span of the segments' stamped usable points as their kept figures
    hold it, and the segments with GPS fixes without a position and how many;
    JIT compiling off for the transaction in the same statement.

    The first time of the usable points (robot clock, else arrival) is at or
    before the first robot stamp.  The last point in driving order carries the
    latest robot stamp unless it has none (unstamped points sort last); then
    the latest time of all is at or after it, and the segment has usable
    points without a robot stamp: only then is the default partition read."""
    return (
        "SELECT set_config('jit', 'off', true), min(first_stamp), "
        "max(COALESCE(last_robot_stamp, last_stamp)), "
        "COALESCE(bool_or(points > 0 AND last_robot_stamp IS NULL), false), "
        "array_agg(segment_id) FILTER (WHERE no_fix > 0), "
        "array_agg(no_fix) FILTER (WHERE no_fix > 0) "
        f'FROM "{SegmentFigures._meta.db_table}" '
        "WHERE segment_id = ANY(%(ids)s::bigint[]) AND mode = %(mode)s"
    )


def _packed_rows(query, segment_ids: list[int], kept_mode: str | None):
    """The rows of ``query(unstamped)`` (``_in_span``), in binary (as the bytes
    are stored), and the kept count of fixes without a position by segment
    (None: every pose was read).

    ``kept_mode`` names the figures (telemetry.models.SegmentFigures) whose
    span bounds the read of stamped poses (``_kept_span_sql``); the figures
    are written in the poses' transaction, so every pose
    committed before this read is inside.  A fix without a position may lie
    outside, so their count is the figures'.  None reads every pose, for
    measuring the figures themselves.

    The aggregate keeps its sorted subquery's order; JIT compiling is off for
    the statement, as it costs a plain scan more than it saves (``SET LOCAL``:
    until the end of the caller's transaction where there is one)."""
    with transaction.atomic():
        span, unstamped, no_fix = _span(segment_ids, kept_mode)
        with bound_cursor(binary_results=True) as cursor:
            cursor.execute(query(unstamped), {"ids": segment_ids, **span})
            return cursor.fetchall(), no_fix


def _span(segment_ids: list[int], kept_mode: str | None) -> tuple[dict, bool, dict | None]:
    """The span the read is bounded by, whether it reads unstamped poses, and
    the kept counts of fixes without a position (``_packed_rows``), with JIT
    off for the transaction."""
    with connection.cursor() as cursor:
        if kept_mode is None:
            cursor.execute("SET LOCAL jit = off")
            return _ALL_TIME, True, None
        cursor.execute(_kept_span_sql(), {"ids": segment_ids, "mode": kept_mode})
        _, first, last, unstamped, segments, counts = cursor.fetchone()
    no_fix = dict(zip(segments or [], counts or [], strict=True))
    return {"first": first, "last": last}, unstamped, no_fix


def gps_tracks_plan(segment_ids: list[int], kept_mode: str, analyze: bool = False) -> list[str]:
    """PostgreSQL's plan of the GPS tracks query as ``gps_arrays`` runs it, for
    the benchmark and the tests to show which partitions it reads."""
    explain = "EXPLAIN (ANALYZE, BUFFERS) " if analyze else "EXPLAIN "
    with transaction.atomic():
        span, unstamped, _ = _span(segment_ids, kept_mode)
        with bound_cursor() as cursor:
            cursor.execute(explain + gps_tracks_sql(unstamped), {"ids": segment_ids, **span})
            return [row[0] for row in cursor.fetchall()]


def _seconds(stamps: bytes | None) -> np.ndarray:
    # The same single rounding as PostgreSQL's epoch: exact microseconds, then float.
    micro = np.frombuffer(stamps or b"", dtype=_PG_STAMP) + _PG_EPOCH_MICROSECONDS
    return micro / 1e6


def gps_arrays(segment_ids: list[int], kept_mode: str | None):
    """(segment id, longitudes, latitudes, seconds since 1970, fixes without a
    position) of each segment that has poses, in driving order (``kept_mode``:
    see ``_packed_rows``)."""
    rows, kept_no_fix = _packed_rows(gps_tracks_sql, segment_ids, kept_mode)
    for seg, points, stamps, no_fix in rows:
        points = np.frombuffer(points or b"", dtype=_WKB_POINT)
        if kept_no_fix is not None:
            no_fix = kept_no_fix.pop(seg, 0)
        yield seg, points["x"].astype(float), points["y"].astype(float), _seconds(stamps), no_fix
    for seg, no_fix in (kept_no_fix or {}).items():
        yield seg, np.empty(0), np.empty(0), np.empty(0), no_fix


def local_arrays(segment_ids: list[int], kept_mode: str | None):
    """(segment id, x, y, seconds since 1970, frame) of each segment that has
    local poses, in driving order (``kept_mode``: see ``_packed_rows``)."""
    rows, _ = _packed_rows(local_tracks_sql, segment_ids, kept_mode)
    for seg, x, y, stamps, frame in rows:
        x = np.frombuffer(x, dtype=_PG_FLOAT).astype(float)
        y = np.frombuffer(y, dtype=_PG_FLOAT).astype(float)
        yield seg, x, y, _seconds(stamps), frame or ""
