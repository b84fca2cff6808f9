"""Time and peak memory of the report for a large test event.

10 shifts, 300 master segments (AUTO and ITO alternating, every ITO with one
reason) and 200 000 GPS poses, bulk-created in a throw-away test database of
the configured backend (FTT_DATABASE_URL for PostGIS, else SpatiaLite in
FTT_DATA_DIR).  Measures the statistics alone and the full PDF (without map
tiles, as offline in the field), each with wall time and the peak of Python
allocations (tracemalloc, includes numpy arrays) plus peak RSS; each stage
runs in a forked child, so the figures are per stage.
BENCH_TRACEMALLOC=1 adds the Python allocation peak (tracemalloc makes the code 2-4x slower).

    .venv/bin/python benchmarks/report_benchmark.py [--shifts 10] [--segments 300]
                                                    [--poses 200000] [--skip-pdf]
                                                    [--repeat N] [--keepdb] [--explain]

The statistics of a million poses (``--segments 1000 --poses 1000000 --skip-pdf``)
have a target of 1 s; the tracks query is timed apart from the whole, and
``--explain`` prints PostgreSQL's plan of that query as it ran.
"""

import argparse
import cProfile
import json
import os
import resource
import sys
import time
import tracemalloc
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

import numpy as np  # noqa: E402
from django.contrib.gis.geos import Point  # noqa: E402
from django.db import connection, transaction  # noqa: E402

from events.models import Leg, Segment, Shift, TestEvent, Vehicle  # noqa: E402
from telemetry.models import Pose  # noqa: E402
from telemetry.selectors.tracks import load_tracks  # noqa: E402
from telemetry.storage.keys import GPS_TRACK  # noqa: E402

try:  # the storage port's PostgreSQL adapter, or a checkout before it
    from telemetry.storage.postgresql import gps_tracks_plan
except ImportError:
    from telemetry.selectors.packed_tracks import gps_tracks_plan
from telemetry.services.segment_figures import measure_figures  # noqa: E402

# Seconds: issue 14's target for the statistics of a million poses.
STATISTICS_TARGET = 1.0

REASONS = ("safety", "planner", "unexpected", "goal", "maintenance")


def _zigzag(count: int) -> np.ndarray:
    """Cumulative latitude offsets of ``count`` one-second steps."""
    p = np.arange(count)
    return np.cumsum(0.000002 * ((p // 50) % 2 * 2 - 1))


def _insert_poses(segments: list[tuple[int, int, float, float, datetime]]) -> None:
    """One pose per second along each segment.  PostgreSQL gets them as arrays in
    one INSERT ... SELECT unnest (seconds for a million rows instead of the
    minutes bulk_create needs); SpatiaLite through bulk_create."""
    ids, xs, ys, stamps = [], [], [], []
    for pk, count, x0, y0, t0 in segments:
        ids.append(np.full(count, pk, dtype=np.int64))
        xs.append(x0 + 0.00001 * np.arange(1, count + 1))
        ys.append(y0 + _zigzag(count))
        stamps.append(t0.timestamp() + np.arange(1, count + 1, dtype=float))
    if not ids:
        return
    ids, xs, ys, stamps = (np.concatenate(a) for a in (ids, xs, ys, stamps))
    if connection.vendor == "postgresql":
        with connection.cursor() as cursor:
            cursor.execute(
                f'INSERT INTO "{Pose._meta.db_table}" '
                "(uid, segment_id, point, robot_stamp, received, fix_status) "
                "SELECT gen_random_uuid(), s, ST_SetSRID(ST_MakePoint(x, y), 4326), "
                "to_timestamp(t), to_timestamp(t), 0 "
                "FROM unnest(%s::int8[], %s::float8[], %s::float8[], %s::float8[])"
                " AS u(s, x, y, t)",
                [ids.tolist(), xs.tolist(), ys.tolist(), stamps.tolist()],
            )
        return
    Pose.objects.bulk_create(
        (
            Pose(
                uid=uuid.uuid4(),
                segment_id=int(pk),
                point=Point(float(x), float(y), srid=4326),
                robot_stamp=datetime.fromtimestamp(float(t), UTC),
                received=datetime.fromtimestamp(float(t), UTC),
            )
            for pk, x, y, t in zip(ids, xs, ys, stamps, strict=True)
        ),
        batch_size=5000,
    )


def build(shifts: int, segments: int, poses: int) -> TestEvent:
    start = datetime(2026, 6, 1, 6, 0, tzinfo=UTC)
    event = TestEvent.objects.create(
        location=_location(shifts, segments, poses), time_zone="Europe/Berlin", start=start
    )
    vehicle, _ = Vehicle.objects.get_or_create(
        key="bench", defaults={"short_description": "Bench vehicle"}
    )
    per_shift = segments // shifts
    index = 0
    lon, lat = 7.0, 50.0
    t = start
    pose_rows = []
    for s in range(shifts):
        shift = Shift.objects.create(
            test_event=event, vehicle=vehicle, number=s + 1, start=t, end=None
        )
        leg = Leg.objects.create(shift=shift, number=1, start=t, weather_id="sunny")
        masters = []
        for k in range(per_shift):
            # Spread the poses exactly: the first (poses % segments) get one more.
            per_segment = poses // segments + (1 if index < poses % segments else 0)
            seconds_per_segment = per_segment  # one pose per second
            index += 1
            kind = "auto" if k % 2 == 0 else "ito"
            masters.append(
                Segment(
                    leg=leg,
                    segment_type_id=kind,
                    start=t,
                    end=t + timedelta(seconds=seconds_per_segment),
                    start_position=Point(lon, lat, srid=4326),
                )
            )
            pose_rows.append((len(masters) - 1, per_segment, lon, lat, t))
            # about 0.7 m east per second, zig-zagging north and south every 50 s
            lon += 0.00001 * per_segment
            lat += _zigzag(per_segment)[-1] if per_segment else 0.0
            t += timedelta(seconds=seconds_per_segment)
        Segment.objects.bulk_create(masters, batch_size=500)
        children = [
            Segment(
                leg=leg,
                parent=m,
                segment_type_id="ito",
                ito_reason_id=REASONS[i % len(REASONS)],
                start=m.start,
                end=m.end,
            )
            for i, m in enumerate(masters)
            if m.segment_type_id == "ito"
        ]
        Segment.objects.bulk_create(children, batch_size=500)
        _insert_poses(
            [(masters[i].pk, n, x0, y0, t0) for i, n, x0, y0, t0 in pose_rows],
        )
        pose_rows.clear()
        # The figures the write path keeps (the report and the track reads use them).
        with transaction.atomic():
            measure_figures([m.pk for m in masters], (GPS_TRACK,))
        Shift.objects.filter(pk=shift.pk).update(end=t)
        Leg.objects.filter(pk=leg.pk).update(end=t)
        t += timedelta(hours=1)
    TestEvent.objects.filter(pk=event.pk).update(end=t)
    event.refresh_from_db()
    return event


def _database_cpu() -> float | None:
    """CPU seconds the PostgreSQL backend of this connection has used so far (its
    /proc entry; the server runs on this machine), None where that is unknown."""
    if connection.vendor != "postgresql":
        return None
    with connection.cursor() as cursor:
        cursor.execute("SELECT pg_backend_pid()")
        pid = cursor.fetchone()[0]
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    # utime and stime are fields 14 and 15 of /proc/PID/stat, in clock ticks.
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(label: str, func) -> dict:
    """Run ``func`` in a forked child: wall time, and the child's peak RSS and
    Python allocation peak, so one stage's memory does not hide the next's."""
    connection.close()  # the child opens its own connection
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        code = 0
        try:
            if os.environ.get("BENCH_TRACEMALLOC") == "1":
                tracemalloc.start()
            db_before = _database_cpu()
            before = resource.getrusage(resource.RUSAGE_SELF)
            cpu_before = before.ru_utime + before.ru_stime
            started = time.perf_counter()
            note = func() or ""
            seconds = time.perf_counter() - started
            _, peak = tracemalloc.get_traced_memory()
            usage = resource.getrusage(resource.RUSAGE_SELF)
            rss = usage.ru_maxrss / 1024
            # CPU seconds of this process (not the database server's): on a shared
            # machine they vary far less with the load than the wall time.
            cpu = usage.ru_utime + usage.ru_stime - cpu_before
            db_after = _database_cpu()
            db = None if db_before is None or db_after is None else db_after - db_before
            out = {
                "seconds": seconds,
                "cpu": cpu,
                "db": db,
                "peak": peak / 2**20,
                "rss": rss,
                "note": note,
            }
        except Exception as exc:  # report, do not hang the parent
            out = {"error": repr(exc)}
            code = 1
        os.write(write_end, json.dumps(out).encode())
        os._exit(code)
    os.close(write_end)
    with os.fdopen(read_end) as pipe:
        out = json.loads(pipe.read() or "{}")
    os.waitpid(pid, 0)
    if "error" in out:
        print(f"{label:<28} failed: {out['error']}")
        return out
    print(
        f"{label:<28} {out['seconds']:8.2f} s (CPU {out['cpu']:6.2f} s"
        + ("" if out["db"] is None else f", database server CPU {out['db']:5.2f} s")
        + ")"
        f"   peak Python alloc {out['peak']:7.1f} MiB"
        f"   peak RSS {out['rss']:7.1f} MiB   load average {os.getloadavg()[0]:.2f}"
        f"   {out['note']}"
    )
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--shifts", type=int, default=10)
    parser.add_argument("--segments", type=int, default=300)
    parser.add_argument("--poses", type=int, default=200_000)
    parser.add_argument("--skip-pdf", action="store_true")
    parser.add_argument(
        "--repeat", type=int, default=1, help="runs of each stage (for the best and the median)"
    )
    parser.add_argument(
        "--explain", action="store_true", help="print the plan of the tracks query (PostgreSQL)"
    )
    parser.add_argument(
        "--keepdb",
        action="store_true",
        help="keep the test database and reuse an event of the same size from an earlier run",
    )
    parser.add_argument("--profile", metavar="FILE", help="cProfile the PDF run into FILE")
    args = parser.parse_args()

    from reports.documents.event_report import render_report
    from reports.documents.options import ReportOptions
    from reports.selectors.statistics import event_statistics

    backend = connection.vendor
    old_name = connection.creation.create_test_db(
        verbosity=0, autoclobber=True, serialize=False, keepdb=args.keepdb
    )
    try:
        started = time.perf_counter()
        location = _location(args.shifts, args.segments, args.poses)
        event = TestEvent.objects.filter(location=location).first() if args.keepdb else None
        if event is None:
            event = build(args.shifts, args.segments, args.poses)
        masters = Segment.objects.filter(parent=None, leg__shift__test_event=event).count()
        poses = Pose.objects.filter(segment__leg__shift__test_event=event).count()
        print(
            f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; "
            f"backend {backend}: {args.shifts} shifts, {masters} master segments, {poses} poses"
            f" (bulk-created in {time.perf_counter() - started:.1f} s)"
        )
        if backend == "postgresql":
            # What autovacuum does to a table that has stopped growing; until then
            # an index-only scan still visits the table pages written last.
            started = time.perf_counter()
            with connection.cursor() as cursor:
                cursor.execute(f'VACUUM ANALYZE "{Pose._meta.db_table}"')
            print(f"VACUUM ANALYZE of the poses in {time.perf_counter() - started:.1f} s")
        master_ids = list(
            Segment.objects.filter(parent=None, leg__shift__test_event=event).values_list(
                "pk", flat=True
            )
        )

        def profiled(stage, func, *a):
            """``func(*a)``, with --profile its cProfile written to FILE.stage."""
            if not args.profile:
                return func(*a)
            profiler = cProfile.Profile()
            try:
                return profiler.runcall(func, *a)
            finally:
                profiler.dump_stats(f"{args.profile}.{stage}")

        def statistics():
            overall = profiled("statistics", event_statistics, event).overall
            return f"{overall.total_distance / 1000:.2f} km, {overall.interventions} interventions"

        def tracks():
            loaded = profiled("tracks", load_tracks, master_ids, GPS_TRACK)
            return f"{sum(len(t) for t in loaded.values())} points of {len(loaded)} segments"

        def api_json():
            return f"{len(json.dumps(event_statistics(event).as_dict())) / 1024:.0f} KiB JSON"

        def pdf():
            result = profiled("pdf", lambda: render_report(event, ReportOptions(no_tiles=True)))
            out = Path(os.environ.get("FTT_DATA_DIR", "data")) / "benchmark-report.pdf"
            out.write_bytes(result.pdf)
            rows = [
                f"    {name:<38} {wall:6.2f} s (CPU {cpu:5.2f} s)"
                for name, wall, cpu in result.stages.rows()
            ]
            rest = result.seconds - sum(wall for _name, wall, _cpu in result.stages.rows())
            rows.append(f"    {'rest (segments, tables, JSON)':<38} {rest:6.2f} s")
            return f"{len(result.pdf) / 2**20:.1f} MiB PDF: {out}\n" + "\n".join(rows)

        if args.explain:
            explain(master_ids)
        runs = [measure("statistics (selectors)", statistics) for _ in range(args.repeat)]
        summarise("statistics", runs, STATISTICS_TARGET if args.poses >= 1_000_000 else None)
        tracks_runs = [measure("  of which tracks query", tracks) for _ in range(args.repeat)]
        summarise("tracks query", tracks_runs)
        measure("statistics as API JSON", api_json)
        if not args.skip_pdf:
            summarise(
                "full PDF", [measure("full PDF report (no tiles)", pdf) for _ in range(args.repeat)]
            )
    finally:
        connection.close()
        if not args.keepdb:
            connection.creation.destroy_test_db(old_name, verbosity=0)


def summarise(label: str, runs: list[dict], target: float | None = None) -> None:
    """Best and median of repeated measurements (wall, own CPU, database CPU)."""
    runs = [r for r in runs if "error" not in r]
    if len(runs) < 2:
        return
    parts = []
    for key, name in (("seconds", "wall"), ("cpu", "CPU"), ("db", "database CPU")):
        values = [r[key] for r in runs if r.get(key) is not None]
        if values:
            parts.append(f"{name} best {min(values):.2f} s, median {np.median(values):.2f} s")
    goal = "" if target is None else f"   (target <= {target:.0f} s wall)"
    print(f"{label} over {len(runs)} runs: " + "; ".join(parts) + goal)


def explain(master_ids: list[int]) -> None:
    """PostgreSQL's plan of the tracks query, run once with EXPLAIN ANALYZE."""
    if connection.vendor != "postgresql":
        return
    print("\n".join(line[:160] for line in gps_tracks_plan(master_ids, GPS_TRACK, analyze=True)))


def _location(shifts: int, segments: int, poses: int) -> str:
    """Names the event by its size, so --keepdb finds the one it built before."""
    return f"benchmark {shifts} shifts, {segments} segments, {poses} poses"


if __name__ == "__main__":
    main()
