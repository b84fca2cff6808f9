"""The cockpit on a long leg: what a live update costs the page's main thread.

Starts the production server of each checkout named (--main, a worktree of
main, and this one) on a fresh SpatiaLite file with a leg of --segments master
segments (half take-overs with their reasons, 200 GPS fixes each), opens the
cockpit in Chromium (1024x768, touch), then lets the robot switch mode
--switches times, --gap seconds apart, with a batch of 20 positions every
0.5 s, and prints per checkout: the main thread's busy share during that
time (Chrome's TaskDuration over wall time) and switch -> shown (the banner
says the new mode), median / max ms.
Run: .venv/bin/python benchmarks/long_leg.py --main /work/main [--segments 250]
"""

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_ALLOW_ASYNC_UNSAFE", "true")

from playwright.sync_api import sync_playwright  # noqa: E402

from benchmarks.cockpit_setup import OPERATOR_AND_SHIFT  # noqa: E402
from tests.support.browser import PASSWORD, Server, login, system_chromium  # noqa: E402

SETUP = (
    OPERATOR_AND_SHIFT
    + """
leg = logs.create_leg(shift=s, weather_id="sunny")
for i in range({segments}):
    master = segments.report_mode(leg, "ito" if i % 2 else "auto").master
    fixes = [pose_writes.GpsFix(7.0 + i * 1e-3, 50.0 + j * 1e-5) for j in range(200)]
    pose_writes.store_poses(master, fixes)
from rosbridge_app.services import collectors
collectors.heartbeat("bench-collector", vehicle=v, logging=True, leg=leg)
print(json.dumps({{"event": e.pk, "shift": s.pk, "leg": leg.pk}}))
"""
)

SWITCH = """
import time
from events.models import Leg
from events.services import segments
master = segments.report_mode(Leg.objects.get(pk={leg}), {mode!r}).master
print(time.time(), master.pk)
"""

POSES = """
from events.models import Segment
from telemetry.services import pose_writes
fixes = [pose_writes.GpsFix(7.5 + {k} * 1e-5, 50.0 + j * 1e-6) for j in range(20)]
pose_writes.store_poses(Segment.objects.get(pk={master}), fixes)
"""

SHOWN = "(mode) => document.querySelector('#mode-panel').dataset.mode === mode"
DRAWN = "#gps-map[data-tracks]:not([data-tracks='0'])"


def measure(root: Path, args) -> dict:
    server = Server(Path(tempfile.mkdtemp()), "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png", root=root)
    server.start()
    try:
        ids = json.loads(
            server.python(SETUP.format(password=PASSWORD, segments=args.segments))
            .strip()
            .splitlines()[-1]
        )
        with sync_playwright() as p:
            exe = system_chromium()
            browser = p.chromium.launch(
                **({"executable_path": exe} if exe else {}), args=["--no-sandbox"]
            )
            page = browser.new_page(
                viewport={"width": 1024, "height": 768}, has_touch=True, is_mobile=True
            )
            page.route("**/tiles/**", lambda r: r.fulfill(status=404))
            login(page, server, "otto")
            page.goto(f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}")
            page.wait_for_selector(DRAWN, state="attached", timeout=60000)
            page.wait_for_function(
                "() => document.querySelector('#mode-panel').dataset.link === 'live'", timeout=30000
            )
            cdp = page.context.new_cdp_session(page)
            cdp.send("Performance.enable")

            def busy() -> float:
                metrics = {
                    m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]
                }
                return metrics["TaskDuration"]

            latencies = []
            mode = "ito" if args.segments % 2 else "auto"
            start_busy, start_wall = busy(), time.time()
            for k in range(args.switches):
                mode = "auto" if mode == "ito" else "ito"
                stamp, master = server.python(SWITCH.format(leg=ids["leg"], mode=mode)).split()
                page.wait_for_function(SHOWN, arg=mode, polling="raf", timeout=30000)
                latencies.append((time.time() - float(stamp)) * 1000)
                until = time.time() + args.gap
                n = 0
                while time.time() < until:
                    server.python(POSES.format(master=master, k=k * 100 + n))
                    n += 1
                    time.sleep(max(0.0, min(0.5, until - time.time())))
            share = (busy() - start_busy) / (time.time() - start_wall) * 100
            browser.close()
        return {"busy": share, "latencies": latencies}
    finally:
        server.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--main", type=Path, help="a checkout of main to measure beside this one")
    parser.add_argument("--segments", type=int, default=250)
    parser.add_argument("--switches", type=int, default=10)
    parser.add_argument("--gap", type=float, default=3.0)
    args = parser.parse_args()
    runs = [("main", args.main)] if args.main else []
    runs.append(("this checkout", ROOT))
    for name, root in runs:
        r = measure(root, args)
        lat = r["latencies"]
        print(
            f"{name}: {args.segments} segments, main thread busy {r['busy']:.1f} %, "
            f"switch -> shown median {statistics.median(lat):.0f} / max {max(lat):.0f} ms "
            f"(n = {len(lat)})",
            flush=True,
        )


if __name__ == "__main__":
    main()
