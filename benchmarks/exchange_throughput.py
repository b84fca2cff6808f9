"""How fast ftt_export / ftt_import move a large test event, into the configured database.

Builds a throw-away test event with one leg of N GPS poses and N local poses
(default 100 000 each) spread over 20 segments, exports it, deletes it,
imports the archive, imports it again (nothing to do) and deletes it again.
Prints the archive size and the time and rate of each step.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/exchange_throughput.py [--poses N]
"""

import argparse
import os
import sys
import tempfile
import time
from datetime import UTC, datetime, timedelta
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

from django.db import connection  # noqa: E402

from events.models import TestEvent, Vehicle  # noqa: E402
from events.services import logs, segments  # noqa: E402
from exchange.archive import open_archive  # noqa: E402
from exchange.export import export_events  # noqa: E402
from exchange.importer import import_bundle  # noqa: E402
from telemetry.services import pose_writes  # noqa: E402

SEGMENTS = 20


def build(n: int) -> TestEvent:
    t0 = datetime(2026, 1, 5, 8, tzinfo=UTC)
    vehicle, _ = Vehicle.objects.get_or_create(key="bench-xchg", short_description="bench")
    event = logs.create_test_event(at=t0, location="benchmark")
    shift = logs.create_shift(test_event=event, vehicle=vehicle, at=t0)
    leg = logs.create_leg(shift=shift, at=t0)
    per = n // SEGMENTS
    for s in range(SEGMENTS):
        at = t0 + timedelta(seconds=1 + s * per)
        master = segments.report_mode(leg, ("ito", "auto")[s % 2], at=at).master
        pose_writes.store_poses(
            master,
            [
                pose_writes.GpsFix(
                    longitude=7.0 + (s * per + k) * 1e-6,
                    latitude=50.0,
                    robot_stamp=at + timedelta(seconds=k),
                )
                for k in range(per)
            ],
        )
        pose_writes.store_local_poses(
            master,
            [
                pose_writes.MapPose(
                    x=k * 0.1, y=s, frame="map", robot_stamp=at + timedelta(seconds=k)
                )
                for k in range(per)
            ],
        )
    logs.close_test_event(event, at=t0 + timedelta(seconds=n + 10))
    return event


def timed(label: str, rows: int, action):
    start = time.perf_counter()
    result = action()
    seconds = time.perf_counter() - start
    print(f"{label:28} {seconds:8.2f} s  {rows / seconds:10.0f} rows/s")
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--poses", type=int, default=100_000)
    n = parser.parse_args().poses
    rows = 2 * n
    print(f"database: {connection.vendor}; {n} poses + {n} local poses in {SEGMENTS} segments")
    event = timed("build (services)", rows, lambda: build(n))
    with tempfile.TemporaryDirectory() as scratch:
        archive = Path(scratch) / "bench.zip"
        timed("export", rows, lambda: export_events(archive, [event]))
        print(f"{'archive size':28} {archive.stat().st_size / 1e6:8.1f} MB")
        event.delete()

        def load():
            with open_archive(archive) as bundle:
                return import_bundle(bundle)

        timed("verify + import (empty)", rows, load)
        plan = timed("verify + import (again)", rows, load)
        assert plan.changes() == 0
    TestEvent.objects.filter(location="benchmark").delete()
    Vehicle.objects.filter(key="bench-xchg").delete()


if __name__ == "__main__":
    main()
