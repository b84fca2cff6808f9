"""How long one mode report takes (alternating AUTO/ITO on one leg), in process.

Issue 26 measured the change history's cost with it, side by side with the
commit before (docs/report.md, Change history).  A throw-away test event is
made and deleted again.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/mode_reports.py [--reports N]
"""

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

from events.models import Vehicle  # noqa: E402
from events.services import logs, segments  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reports", type=int, default=300)
    n = parser.parse_args().reports
    vehicle, _ = Vehicle.objects.get_or_create(
        key="bench-modes", defaults={"short_description": "benchmark"}
    )
    event = logs.create_test_event(location="bench modes")
    leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
    times = []
    try:
        for i in range(n):
            started = time.perf_counter()
            segments.report_mode(leg, "ito" if i % 2 else "auto")
            times.append(time.perf_counter() - started)
    finally:
        logs.close_test_event(event)
        event.delete()
        vehicle.delete()
    load = os.getloadavg()[0]
    print(
        f"report_mode: median {statistics.median(times) * 1000:.2f} ms, "
        f"mean {statistics.mean(times) * 1000:.2f} ms over {n} (load average {load:.1f})"
    )


if __name__ == "__main__":
    main()
