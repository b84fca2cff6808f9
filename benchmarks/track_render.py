"""How fast a big leg's tracks are on screen: navigation -> all tracks drawn.

Builds a leg with --poses GPS poses and as many local poses (--segments master
segments) on the configured database (FTT_DATABASE_URL or --database-url;
otherwise a fresh SpatiaLite file), starts the server as the browser tests do, and
opens the cockpit in Chromium at 1366x768 --repeat times.

"Drawn" is the map's own mark (TrackMap.markDrawn in static/gui/maps.js): an
animation frame after the canvas renderer's, once both maps hold every point
of the tracks response; the figure is that frame's time since navigation
(performance.now()), taken after the page has been quiet for half a second, so
a later re-render (fitting the view) counts.  Then the GPS map is zoomed in
three levels with its + button and the time until the detail for the area in
view is drawn is measured the same way.  Target: <= 1 s from navigation.

Each visit's figure is split into the page's start-up until the tracks
request leaves, the wait for its first byte, the transfer, and decoding plus
drawing; the bytes transferred are printed (the tracks answer and the whole
visit).  ``--against /work/main`` runs a second server from another checkout
on the same database and leg and alternates the visits, for an A/B comparison
under the same load.

A cold visit is the first one to a freshly started server, from a fresh
browser (nothing cached): what a field team sees when it opens a leg after the
server (re)started.  Each long-running server's first visit is one; ``--cold
N`` adds N more, each on a server started for it and stopped after it
(alternating with the other checkout).  The warm figures are the later
visits to the long-running servers.  The load average is printed with every
visit.

Run: .venv/bin/python benchmarks/track_render.py [--repeat 5] [--cold 2] [--poses 200000]
     [--keep | --reuse EVENT,SHIFT,LEG] [--against /path/to/other/checkout]
     [--port 18400]
"""

import argparse
import itertools
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

from tests.support.browser import ROOT as CHECKOUT  # noqa: E402
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
from telemetry.services import pose_writes
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
        fixes.append(pose_writes.GpsFix(7.0 + x / 71700 + noise[0], 50.0 + y / 111200 + noise[1],
                                      robot_stamp=stamp))
        local.append(pose_writes.MapPose(x + noise[0] * 1e5, y + noise[1] * 1e5, "map",
                                       robot_stamp=stamp))
    for first in range(0, per, 10000):
        pose_writes.store_poses(master, fixes[first:first + 10000])
        pose_writes.store_local_poses(master, local[first:first + 10000])
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

# Bytes the visit fetched from the server (page, modules, styles, API answers),
# headers included; what came from the browser's cache counts 0.
TRANSFERRED = """() => [...performance.getEntriesByType("navigation"),
                    ...performance.getEntriesByType("resource")]
  .reduce((sum, r) => sum + (r.transferSize || 0), 0)"""


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


def one_visit(page, url) -> dict:
    """Navigation -> both maps drawn, then three zoom-in taps -> detail drawn."""
    seen = []
    page.on("requestfinished", lambda r: "/tracks/" in r.url and seen.append(r))
    page.goto(url, wait_until="commit", timeout=120_000)
    while not seen:
        page.wait_for_timeout(20)
    body = json.loads(seen[0].response().body())
    want = [
        sum(len(s["gps"]) for s in body["segments"].values()),
        sum(len(s["local"]) for s in body["segments"].values()),
    ]
    gps_at, local_at = quiet_mark(page, DRAWN, want)
    drawn = max(gps_at, local_at)
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
    resources = page.evaluate(RESOURCES)
    transferred = page.evaluate(TRANSFERRED)
    whole = next(r for r in resources if "fit=" in r[0])
    _, start, first, end, packed, plain = whole
    return {
        "drawn": drawn,
        "points": want,
        "zoom": mark[1] - clicked,
        "zoom_level": mark[0],
        "details": len([r for r in seen[before:] if "map=gps" in r.url]),
        # The split of "drawn": page start-up until the tracks request leaves,
        # waiting for the server's first byte, the transfer, then decoding,
        # drawing and fitting until the canvas mark.
        "start": start,
        "wait": first - start,
        "transfer": end - first,
        "draw": drawn - end,
        "bytes": (packed, plain),
        "transferred": transferred,
        "resources": resources,
        "load": os.getloadavg()[0],
    }


def print_visit(label, kind, visit):
    for name, start, first, end, packed, plain in visit["resources"]:
        print(f"  {start:6.0f} {first:6.0f} {end:6.0f} {packed:9d} {plain:9d}  {name}")
    print(
        f"{kind} visit ({label}, load {visit['load']:.2f}): drawn {visit['drawn']:.0f} ms after "
        f"navigation (tracks request leaves at {visit['start']:.0f} ms, first byte after "
        f"{visit['wait']:.0f} ms, transfer {visit['transfer']:.0f} ms, decode and draw "
        f"{visit['draw']:.0f} ms; {visit['points'][0]} + {visit['points'][1]} points; "
        f"{visit['transferred']} bytes transferred until drawn); zoom-in detail (zoom "
        f"{visit['zoom_level']}) drawn {visit['zoom']:.0f} ms after the first tap, "
        f"{visit['details']} detail request(s)",
        flush=True,
    )


def summary(label, checkout, cold, warm):
    print(f"{label} ({checkout}): {len(cold)} cold visits, {len(warm)} warm visits")
    print(f"  {'what':48} {'cold median':>11} {'cold max':>8} {'warm median':>11} {'warm p95':>8}")
    rows = (
        ("navigation -> all tracks drawn", "drawn"),
        ("  of which: until the tracks request leaves", "start"),
        ("  of which: waiting for its first byte", "wait"),
        ("  of which: its transfer", "transfer"),
        ("  of which: decode, draw and fit", "draw"),
        ("zoom in 3 levels -> detail in view drawn", "zoom"),
    )
    for what, key in rows:
        figures = []
        for runs, high in ((cold, max), (warm, lambda v: percentile(v, 0.95))):
            values = [r[key] for r in runs]
            figures += [statistics.median(values), high(values)] if values else [0, 0]
        print(
            f"  {what:48} {figures[0]:11.0f} {figures[1]:8.0f} {figures[2]:11.0f} {figures[3]:8.0f}"
        )
    print(f"  target: navigation -> drawn <= {TARGET_MS} ms, cold and warm")
    for kind, runs in (("cold", cold), ("warm", warm)):
        if runs:
            sent = statistics.median(r["transferred"] for r in runs)
            print(f"  {kind}: median {sent:.0f} bytes transferred from navigation until drawn")
    packed, plain = (cold or warm)[0]["bytes"]
    print(f"  whole-leg answer: {packed} bytes transferred (gzip), {plain} bytes JSON")
    chosen = [r for v in cold + warm for r in v["resources"] if "map=gps" in r[0]]
    if chosen:
        took = statistics.median(end - start for _, start, _, end, _, _ in chosen)
        print(
            f"  area-in-view answer: median {took:.0f} ms, {chosen[0][4]} bytes transferred "
            f"(gzip), {chosen[0][5]} bytes JSON"
        )
    loads = [r["load"] for r in cold + warm]
    print(f"  load average (1 min) during the visits: {min(loads):.2f}-{max(loads):.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="visits per long-running server")
    parser.add_argument(
        "--cold", type=int, default=0, help="more cold visits, each to a server started for it"
    )
    parser.add_argument("--poses", type=int, default=200_000)
    parser.add_argument("--segments", type=int, default=20)
    parser.add_argument("--database-url", default=os.environ.get("FTT_DATABASE_URL", ""))
    parser.add_argument("--keep", action="store_true", help="keep the leg (prints its ids)")
    parser.add_argument("--reuse", help="event,shift,leg of a kept leg: skip building")
    parser.add_argument("--screenshots", help="folder for the cockpit at three sizes, to look at")
    parser.add_argument(
        "--against",
        help="another checkout (e.g. /work/main): its server runs beside this one on the "
        "same database and leg, visits alternate, and the figures are compared",
    )
    parser.add_argument(
        "--port", type=int, help="servers listen on the 100 ports from this one (else any free)"
    )
    args = parser.parse_args()
    tag = str(os.getpid())
    data = Path(tempfile.mkdtemp(prefix="ftt-bench-"))
    tiles = "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png"
    ports = itertools.cycle(range(args.port, args.port + 100)) if args.port else None
    labels = ["this", "against"] if args.against else ["this"]
    checkouts = {"this": CHECKOUT, "against": Path(args.against or ".").resolve()}

    def new_server(label: str) -> Server:
        # One data folder: all servers share the secret key, so one session cookie serves all.
        server = Server(
            data,
            tiles,
            database_url=args.database_url,
            name="track-render" if label == "this" else "track-render-against",
            root=checkouts[label],
        )
        if ports is not None:
            server.port = next(ports)
            server.url = f"http://127.0.0.1:{server.port}"
        server.start()
        return server

    servers = {}
    ids = None
    cold = {label: [] for label in labels}
    warm = {label: [] for label in labels}
    try:
        for label in labels:
            servers[label] = new_server(label)
        server = servers["this"]
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
        query = f"/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}"
        with sync_playwright() as p:
            exe = os.environ.get("FTT_CHROMIUM") or system_chromium()
            browser = p.chromium.launch(**({"executable_path": exe} if exe else {}))

            def new_context(each: Server):
                context = browser.new_context(viewport={"width": 1366, "height": 768})
                context.add_cookies(
                    [{"name": "sessionid", "value": ids["session"], "url": each.url}]
                )
                context.route("**/tiles/**", lambda route: route.fulfill(status=404))
                return context

            # The long-running servers' browser: later visits find its cache.
            contexts = {label: new_context(each) for label, each in servers.items()}
            for run in range(args.repeat):
                for label, each in servers.items():
                    page = contexts[label].new_page()
                    visit = one_visit(page, each.url + query)
                    page.close()
                    kind = "cold" if run == 0 else "warm"
                    (cold if run == 0 else warm)[label].append(visit)
                    print_visit(label, f"{kind} {run + 1}", visit)
            for run in range(args.cold):
                for label in labels:
                    fresh = new_server(label)
                    try:
                        context = new_context(fresh)
                        visit = one_visit(context.new_page(), fresh.url + query)
                        context.close()
                    finally:
                        fresh.stop()
                    cold[label].append(visit)
                    print_visit(label, f"cold (restart {run + 1})", visit)
            if args.screenshots:
                shots(contexts["this"], server.url + query, Path(args.screenshots))
            browser.close()
    finally:
        if ids is not None and args.database_url and not (args.keep or args.reuse):
            servers["this"].python(CLEANUP.format(event=ids["event"], tag=tag))
        for each in servers.values():
            each.stop()
    load = os.getloadavg()
    print(
        f"database: {'PostGIS' if args.database_url else 'SpatiaLite'} · {os.cpu_count()} cores · "
        f"load average now {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}"
    )
    for label in labels:
        summary(label, checkouts[label], cold[label], warm[label])
    if args.against:
        for key, what in (("drawn", "navigation -> drawn"), ("zoom", "zoom-in detail")):
            for kind, runs in (("cold", cold), ("warm", warm)):
                if runs["this"] and runs["against"]:
                    this = statistics.median(r[key] for r in runs["this"])
                    other = statistics.median(r[key] for r in runs["against"])
                    print(f"ratio this / against, {what}, {kind}: {this / other:.2f}")


if __name__ == "__main__":
    main()
