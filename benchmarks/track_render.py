"""How fast a big leg's tracks are on screen: navigation -> all tracks drawn.

Builds a leg with --poses GPS poses and as many local poses (--segments master
segments) on the configured database (FTT_DATABASE_URL or --database-url;
otherwise a fresh SpatiaLite file), starts daphne as the browser tests do, and
opens the cockpit in Chromium at 1366x768 --repeat times.

"Drawn" is the map's own mark (TrackMap.markDrawn in static/gui/maps.js): an
animation frame after the canvas renderer's, once both maps hold every point
of the tracks response; the figure is that frame's time since navigation
(performance.now()), taken after the page has been quiet for half a second, so
a later re-render (fitting the view) counts.  Then the GPS map is zoomed in
three levels with its + button and the time until the detail for the area in
view is drawn is measured the same way.  Target: <= 1 s from navigation.

Run: .venv/bin/python benchmarks/track_render.py [--repeat 5] [--poses 200000]
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

from tests.support.browser import Server, session_code, system_chromium  # noqa: E402

TARGET_MS = 1000

# Loops around a field with a slow wobble and 2 cm of GPS noise, 10 Hz for
# --poses / 10 seconds; the local track follows the same drive in metres.
SETUP = """
s_key = s.session_key
import json, math, random
from datetime import timedelta
from django.db import connection
from django.utils import timezone
from events.models import PoseSource, Vehicle
from events.services import logs, segments
from telemetry.services import recording
PoseSource.objects.get_or_create(key="gps", defaults={{"short_description": "GPS"}})
v = Vehicle.objects.create(key="tracks-{tag}", short_description="Bench rover")
e = logs.create_test_event(location="Track render {tag}", time_zone="Europe/Berlin")
shift = logs.create_shift(test_event=e, vehicle=v)
leg = logs.create_leg(shift=shift, weather_id="sunny")
t0 = timezone.now() - timedelta(hours=8)
rng = random.Random(18)
per = {poses} // {segments}
for k in range({segments}):
    master = segments.report_mode(leg, "auto" if k % 2 == 0 else "ito").master
    fixes, local = [], []
    for j in range(per):
        i = k * per + j
        a = i * 2 * math.pi / 20000
        r = 1 + 0.25 * math.sin(i / 300)
        stamp = t0 + timedelta(seconds=i * 0.1)
        x, y = 300 * r * math.cos(a) + i * 5e-4, 200 * r * math.sin(a)
        noise = rng.gauss(0, 2e-7), rng.gauss(0, 2e-7)
        fixes.append(recording.GpsFix(7.0 + x / 71700 + noise[0], 50.0 + y / 111200 + noise[1],
                                      robot_stamp=stamp))
        local.append(recording.MapPose(x + noise[0] * 1e5, y + noise[1] * 1e5, "map",
                                       robot_stamp=stamp))
    for first in range(0, per, 10000):
        recording.record_poses(master, fixes[first:first + 10000])
        recording.record_local_poses(master, local[first:first + 10000])
if connection.vendor == "postgresql":
    # What autovacuum does shortly after a bulk load: without statistics the
    # planner sorts 200 000 rows on disk instead of reading the time index.
    with connection.cursor() as cursor:
        cursor.execute("ANALYZE telemetry_pose; ANALYZE telemetry_localpose")
print("IDS", json.dumps({{"event": e.pk, "shift": shift.pk, "leg": leg.pk, "session": s_key}}))
"""

REUSE = """
import json
event, shift, leg = [int(v) for v in "{ids}".split(",")]
print("IDS", json.dumps({{"event": event, "shift": shift, "leg": leg, "session": s.session_key}}))
"""

CLEANUP = """
from django.contrib.auth.models import User
from events.models import TestEvent, Vehicle
from events.services import deletion
deletion.delete(TestEvent.objects.get(pk={event}))
deletion.delete(Vehicle.objects.get(key="tracks-{tag}"))
User.objects.filter(username="tracks-{tag}").delete()
"""

# Both maps' marks once they hold `want` points each; null until then.
DRAWN = """([gps, local]) => {
  const g = document.querySelector("#gps-map").dataset;
  const l = document.querySelector("#local-map").dataset;
  if (Number(g.trackPoints) !== gps || Number(l.trackPoints) !== local) return null;
  return [Number(g.drawnAt), Number(l.drawnAt)];
}"""


# The page's own record of the tracks requests, in the clock of the marks.
RESOURCES = """() => performance.getEntriesByType("resource")
  .filter((r) => r.name.includes("/tracks/"))
  .map((r) => [r.name.split("/gui/api/")[1], r.startTime, r.responseStart, r.responseEnd,
               r.encodedBodySize, r.decodedBodySize])"""


def quiet_mark(page, script, arg):
    """The mark once it has not changed for half a second."""
    last, since = None, time.monotonic()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        mark = page.evaluate(script, arg)
        if mark != last:
            last, since = mark, time.monotonic()
        elif mark is not None and time.monotonic() - since > 0.5:
            return mark
        time.sleep(0.05)
    raise TimeoutError(f"the maps never showed {arg} points (last mark {last})")


def shots(context, url, folder: Path):
    """The cockpit with the big leg at the laptop, tablet and phone sizes."""
    folder.mkdir(parents=True, exist_ok=True)
    page = context.new_page()
    for width, height in ((1366, 768), (1024, 768), (390, 844)):
        page.set_viewport_size({"width": width, "height": height})
        page.goto(url, wait_until="commit", timeout=120_000)
        page.wait_for_function(
            "() => document.querySelector('#gps-map').dataset.trackPoints > 0", timeout=120_000
        )
        page.wait_for_timeout(1000)
        page.screenshot(path=str(folder / f"cockpit-{width}x{height}.png"), full_page=True)
    page.close()


def percentile(values, share):
    ordered = sorted(values)
    return ordered[max(0, round(len(ordered) * share) - 1)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--poses", type=int, default=200_000)
    parser.add_argument("--segments", type=int, default=20)
    parser.add_argument("--database-url", default=os.environ.get("FTT_DATABASE_URL", ""))
    parser.add_argument("--keep", action="store_true", help="keep the leg (prints its ids)")
    parser.add_argument("--reuse", help="event,shift,leg of a kept leg: skip building")
    parser.add_argument("--screenshots", help="folder for the cockpit at three sizes, to look at")
    args = parser.parse_args()
    tag = str(os.getpid())
    server = Server(
        Path(tempfile.mkdtemp(prefix="ftt-bench-")),
        "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png",
        database_url=args.database_url,
    )
    server.start()
    ids = None
    loads, zooms, requests = [], [], []
    try:
        started = time.perf_counter()
        if args.reuse:
            code = session_code(f"tracks-{tag}", "viewer") + REUSE.format(ids=args.reuse)
        else:
            code = session_code(f"tracks-{tag}", "viewer") + SETUP.format(
                tag=tag, poses=args.poses, segments=args.segments
            )
        out = server.python(code, timeout=1800)
        ids = json.loads(next(x for x in out.splitlines() if x.startswith("IDS"))[4:])
        print(f"leg ready in {time.perf_counter() - started:.0f} s: {ids}")
        url = f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}"
        with sync_playwright() as p:
            exe = os.environ.get("FTT_CHROMIUM") or system_chromium()
            browser = p.chromium.launch(**({"executable_path": exe} if exe else {}))
            context = browser.new_context(viewport={"width": 1366, "height": 768})
            context.add_cookies([{"name": "sessionid", "value": ids["session"], "url": server.url}])
            context.route("**/tiles/**", lambda route: route.fulfill(status=404))
            for run in range(args.repeat):
                page = context.new_page()
                seen = []
                page.on(
                    "requestfinished", lambda r, seen=seen: "/tracks/" in r.url and seen.append(r)
                )
                page.goto(url, wait_until="commit", timeout=120_000)
                while not seen:
                    page.wait_for_timeout(20)
                overview = seen[0]
                body = json.loads(overview.response().body())
                want = [
                    sum(len(s["gps"]) for s in body["segments"].values()),
                    sum(len(s["local"]) for s in body["segments"].values()),
                ]
                gps_at, local_at = quiet_mark(page, DRAWN, want)
                loads.append(max(gps_at, local_at))
                # Zoom in: the detail of the area in view replaces the thinned line.
                before = len(seen)
                clicked = page.evaluate("performance.now()")
                for _ in range(3):
                    page.locator("#gps-map .leaflet-control-zoom-in").click()
                mark = quiet_mark(
                    page,
                    """() => { const d = document.querySelector("#gps-map").dataset;
                               return d.detailZoom ? [d.detailZoom, Number(d.drawnAt)] : null; }""",
                    None,
                )
                zooms.append(mark[1] - clicked)
                detail = [r for r in seen[before:] if "map=gps" in r.url]
                resources = page.evaluate(RESOURCES)
                requests.extend(resources)
                for name, start, first, end, packed, plain in resources:
                    print(f"  {start:6.0f} {first:6.0f} {end:6.0f} {packed:9d} {plain:9d}  {name}")
                print(
                    f"run {run + 1}: drawn {loads[-1]:.0f} ms after navigation "
                    f"(GPS {gps_at} ms, local {local_at} ms, {want[0]} + {want[1]} points); "
                    f"zoom-in detail (zoom {mark[0]}) drawn {zooms[-1]:.0f} ms "
                    "after the first tap, "
                    f"{len(detail)} detail request(s)"
                )
                page.close()
            if args.screenshots:
                shots(context, url, Path(args.screenshots))
            browser.close()
    finally:
        if ids is not None and args.database_url and not (args.keep or args.reuse):
            server.python(CLEANUP.format(event=ids["event"], tag=tag))
        server.stop()
    load = os.getloadavg()
    print(
        f"database: {'PostGIS' if args.database_url else 'SpatiaLite'} · {os.cpu_count()} cores · "
        f"load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}"
    )
    print(f"{'what':44} {'median ms':>9} {'p95 ms':>7}  target")
    for what, values, target in (
        ("navigation -> all tracks drawn", loads, f"<= {TARGET_MS} ms"),
        ("zoom in 3 levels -> detail in view drawn", zooms, ""),
    ):
        median, p95 = statistics.median(values), percentile(values, 0.95)
        print(f"{what:44} {median:9.0f} {p95:7.0f}  {target}")
    for kind, mark in (("whole leg (fit=)", "fit="), ("area in view (map=gps)", "map=gps")):
        chosen = [r for r in requests if mark in r[0]]
        if chosen:
            took = statistics.median(end - start for _, start, _, end, _, _ in chosen)
            print(
                f"request {kind}: median {took:.0f} ms, {chosen[0][4]} bytes gzipped, "
                f"{chosen[0][5]} bytes JSON"
            )


if __name__ == "__main__":
    main()
