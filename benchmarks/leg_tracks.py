"""One leg's tracks on a campaign database that ``campaign_scale.py --keepdb`` left.

Times ``load_tracks`` for the leg ``campaign_scale`` measures (the first leg
of the middle test event), best of ``--repeat``, in ``--rounds``, and prints
the plan of its pose query with planning and execution time apart
(EXPLAIN (ANALYZE, BUFFERS)) and the round trip of an empty statement, so a
difference between two checkouts can be placed; ``--parts`` splits the read
into its round trips (BEGIN with the statement before the pose query, the
pose query, COMMIT), each best of ``--repeat``.  FTT_DATABASE_URL names the
campaign database itself (``test_…``), FTT_BENCH_ROOT the checkout, as for
``campaign_scale.py``; run the two checkouts alternately, each in a process
of its own:

    FTT_DATABASE_URL=postgis://…/test_ftt_x FTT_BENCH_ROOT=<checkout> \\
        .venv/bin/python benchmarks/leg_tracks.py [--repeat 20] [--rounds 3] [--plan]
"""

import argparse
import inspect
import math
import os
import time

# One connection of its own, not a pool (set before campaign_scale sets Django up).
os.environ.setdefault("FTT_DB_POOL_SIZE", "0")

from campaign_scale import ROOT, one_leg, timed  # noqa: E402
from django.db import connection, transaction  # noqa: E402

from events.models import TestEvent  # noqa: E402
from telemetry.models import Pose  # noqa: E402

try:  # the storage port's PostgreSQL adapter, or a checkout before it
    from telemetry.storage import postgresql as packed_tracks
    from telemetry.storage.postgresql import bound_cursor
except ImportError:
    from common.sql import bound_cursor
    from telemetry.selectors import packed_tracks
from telemetry.selectors.tracks import load_tracks  # noqa: E402
from telemetry.storage.keys import GPS_TRACK  # noqa: E402

POSES = Pose._meta.db_table


def leg_masters() -> list[int]:
    events = list(TestEvent.objects.exclude(location="live").order_by("start"))
    return [m.pk for m in one_leg(events[len(events) // 2])]


def plan(ids: list[int]) -> list[str]:
    """The pose query's plan as load_tracks runs it (before the bound: one parameter)."""
    if hasattr(packed_tracks, "gps_tracks_plan"):
        return packed_tracks.gps_tracks_plan(ids, GPS_TRACK, analyze=True)
    with transaction.atomic(), bound_cursor() as cursor:
        cursor.execute("SET LOCAL jit = off")
        cursor.execute("EXPLAIN (ANALYZE, BUFFERS) " + packed_tracks.gps_tracks_sql(), [ids])
        return [row[0] for row in cursor.fetchall()]


def parts(ids: list[int], repeat: int) -> dict[str, float]:
    """Best seconds of each round trip of one read as ``packed_tracks`` makes
    it (a checkout reads in one statement, or in two in a transaction); the
    rest of ``load_tracks`` is Python (arrays, tracks)."""
    if hasattr(packed_tracks, "_read"):  # one statement, no transaction
        sql, columns = packed_tracks.gps_tracks_sql(), packed_tracks._GPS_COLUMNS
        read = timed(lambda: packed_tracks._read(sql, columns, ids, GPS_TRACK), repeat)
        return {"the one statement": read}
    best = dict.fromkeys(("begin + first statement", "pose query", "commit"), math.inf)
    for _ in range(repeat):
        started = time.perf_counter()
        with transaction.atomic():
            if hasattr(packed_tracks, "_span"):
                span, unstamped, _ = packed_tracks._span(ids, GPS_TRACK)
                query, params = packed_tracks.gps_tracks_sql(unstamped), {"ids": ids, **span}
            else:  # one pose table: JIT off, then the query
                with connection.cursor() as cursor:
                    cursor.execute("SET LOCAL jit = off")
                query, params = packed_tracks.gps_tracks_sql(), [ids]
            first = time.perf_counter()
            with bound_cursor(binary_results=True) as cursor:
                cursor.execute(query, params)
                cursor.fetchall()
            read = time.perf_counter()
        done = time.perf_counter()
        for name, seconds in zip(best, (first - started, read - first, done - read), strict=True):
            best[name] = min(best[name], seconds)
    return best


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--plan", action="store_true", help="print the whole plan")
    parser.add_argument("--parts", action="store_true", help="time each round trip of a read")
    args = parser.parse_args()
    ids = leg_masters()
    points = sum(len(t) for t in load_tracks(ids, GPS_TRACK).values())
    with connection.cursor() as cursor:
        # A plain table is its own tree's one row, not a leaf.
        leaves = "greatest(count(*) FILTER (WHERE isleaf), 1)"
        cursor.execute(f"SELECT {leaves} FROM pg_partition_tree(%s::regclass)", [POSES])
        partitions = cursor.fetchone()[0]
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    print(
        f"checkout {ROOT}; {len(ids)} masters, {points} points; "
        f"{partitions} pose table(s); load {load}"
    )

    def empty():
        with connection.cursor() as cursor:
            cursor.execute("SELECT 1")

    for r in range(args.rounds):
        tracks = timed(lambda: load_tracks(ids, GPS_TRACK), args.repeat)
        trip = timed(empty, args.repeat)
        print(
            f"round {r + 1}: load_tracks {tracks * 1e3:.3f} ms, empty statement {trip * 1e3:.3f} ms"
        )
        if args.parts:
            split = parts(ids, args.repeat)
            print("  parts: " + ", ".join(f"{k} {v * 1e3:.3f} ms" for k, v in split.items()))
    lines = plan(ids)
    timing = [line for line in lines if line.startswith(("Planning", "Execution"))]
    print("; ".join(timing) if not args.plan else "\n".join(lines))
    print("load_tracks arguments:", inspect.signature(load_tracks))


if __name__ == "__main__":
    main()
