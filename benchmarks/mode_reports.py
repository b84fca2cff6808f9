"""How long one mode report takes (alternating AUTO/ITO on one leg), in process.

Issue 26 measured the change history's cost with it, side by side with the
commit before (docs/report.md, Change history).  A throw-away test event is
made and deleted again.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/mode_reports.py [--reports N]

Side by side with another checkout (which needs a copy of this script and a
database of its own, migrated by that checkout): both run as workers at once
and take turns, a block of reports each, so a shared machine's changing load
falls on both alike.

    .venv/bin/python benchmarks/mode_reports.py --reports 300 \\
        --against ../base --against-database postgis://.../ftt_base
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLOCK = 20


def serve() -> None:
    """A worker: one leg; each line "N" on stdin runs N reports and answers their times."""
    sys.path.insert(0, str(ROOT))
    os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")
    import django

    django.setup()
    from events.models import Vehicle
    from events.services import logs, segments

    vehicle, _ = Vehicle.objects.get_or_create(
        key=f"bench-modes-{os.getpid()}", defaults={"short_description": "benchmark"}
    )
    event = logs.create_test_event(location="bench modes")
    leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
    done = 0
    try:
        for line in sys.stdin:
            times = []
            for _ in range(int(line)):
                started = time.perf_counter()
                segments.report_mode(leg, "ito" if done % 2 else "auto")
                times.append(time.perf_counter() - started)
                done += 1
            print(json.dumps(times), flush=True)
    finally:
        logs.close_test_event(event)
        event.delete()
        vehicle.delete()


def _worker(tree: Path, database: str | None) -> subprocess.Popen:
    env = dict(os.environ, **({"FTT_DATABASE_URL": database} if database else {}))
    return subprocess.Popen(
        [sys.executable, str(tree / "benchmarks" / "mode_reports.py"), "--serve"],
        cwd=tree,
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )


def _summary(name: str, times: list[float]) -> str:
    return (
        f"{name}: median {statistics.median(times) * 1000:.2f} ms, "
        f"mean {statistics.mean(times) * 1000:.2f} ms over {len(times)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reports", type=int, default=300)
    parser.add_argument("--against", type=Path, help="another checkout to compare with")
    parser.add_argument("--against-database", help="its FTT_DATABASE_URL")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve:
        return serve()
    trees = {"this checkout": (ROOT, None)}
    if args.against:
        trees[f"against {args.against}"] = (args.against.resolve(), args.against_database)
    workers = {name: _worker(tree, db) for name, (tree, db) in trees.items()}
    times = {name: [] for name in workers}
    try:
        while len(times["this checkout"]) < args.reports:
            for name, worker in workers.items():
                worker.stdin.write(f"{BLOCK}\n")
                worker.stdin.flush()
                times[name] += json.loads(worker.stdout.readline())
    finally:
        for worker in workers.values():
            worker.stdin.close()
            worker.wait()
    for name, measured in times.items():
        print(f"report_mode, {_summary(name, measured)}")
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
