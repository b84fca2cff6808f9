"""A fleet on one server: N simulated robots, each with its collector in its own
ROS domain, one PostGIS, the production server (2 workers, Redis if given) and
headless Chromium on the fleet view (issue 33).

Per N it prints: mode switches stored and their time error against the
robot's switch (the simulator switches every --switch-every s from the start
time it prints), the largest stored uncertainty, GPS fixes missing (published
by the robots vs stored, thinning off) and the collectors' own estimate,
switch -> fleet view on screen p50/p95, the fleet view's open time and the
fleet API's time, CPU and RSS per process kind, and server errors logged.
The robots' share (simulators and collectors, which on a real fleet run on
the robots) is printed apart from the server's.  ``--robot-nice N`` runs the
simulated robots at nice N, to see how much of a switch's time is the robots'
own processes taking the shared cores from FTT's.

    .venv/bin/python benchmarks/fleet.py --database-url postgis://ftt:ftt@127.0.0.1:5432/ftt \\
        [--robots 3 6 10] [--seconds 60] [--redis-url redis://127.0.0.1:6379/2]

It makes (and drops) a database per N next to the one --database-url names.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
# The collector's parameter table names its texts through Django's translations.
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

from tests.support.browser import (  # noqa: E402
    ARTIFACTS,
    Server,
    drop_database,
    fresh_database,
    session_code,
    system_chromium,
)

TICK = os.sysconf("SC_CLK_TCK")
SETUP = """
import json
from events.models import Vehicle
from events.services import logs
legs = []
for i in range({n}):
    v = Vehicle.objects.create(key=f"fleet-{{i}}", short_description=f"Rover {{i}}")
    e = logs.create_test_event(location=f"Fleet {{i}}")
    legs.append(logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v)).pk)
print("SETUP", s.session_key, json.dumps(legs))
"""
RESULTS = """
import json
from events.models import Announcement, Segment
from rosbridge_app.models import Collector
from telemetry.models import Pose
def stored(master):
    # The new segment's first row in the change feed: its id, and when it was written
    # (in the transaction that stored the segment, just before its commit).
    row = Announcement.objects.filter(kind="segment", payload__id=master.pk).order_by("id").first()
    return [row.pk, row.created.timestamp()] if row else [None, None]
out = {{}}
for leg in {legs!r}:
    masters = Segment.objects.masters().filter(leg_id=leg).order_by("start")
    inputs = (Collector.objects.filter(leg_id=leg).values_list("inputs", flat=True).first()) or {{}}
    out[leg] = {{
        "masters": [
            [m.segment_type_id, m.start.timestamp(), m.start_uncertainty, *stored(m)]
            for m in masters
        ],
        "poses": Pose.objects.filter(segment__leg_id=leg).count(),
        "missed": (inputs.get("gps_fix") or {{}}).get("dropped"),
    }}
print("RESULTS", json.dumps(out))
"""
COUNT = """
import json
from django.db.models import Count
from events.models import Segment
rows = Segment.objects.masters().filter(leg_id__in={legs!r}).values("leg_id")
counts = dict(rows.annotate(n=Count("id")).values_list("leg_id", "n"))
print("COUNT", json.dumps(counts))
"""
# Before any page script: when each live message with segment events arrives
# (epoch ms, performance.now() on the page's time origin).
FRAMES = """(() => {
  window.__frames = [];
  const Native = window.WebSocket;
  window.WebSocket = class extends Native {
    constructor(...args) {
      super(...args);
      this.addEventListener("message", (e) => {
        const at = performance.timeOrigin + performance.now();
        const m = JSON.parse(e.data);
        if (m.type !== "events") return;
        const ids = m.events.filter((x) => x.kind === "segment").map((x) => x.id);
        if (ids.length) window.__frames.push([ids, at]);
      });
    }
  };
  // How many vehicles the fleet list shows, each time that changes (ms after
  // navigation), from the first node parsed: the page's modules draw it early.
  window.__list = [];
  new MutationObserver(() => {
    const n = document.querySelectorAll("#fleet-list .fleet-vehicle").length;
    const last = window.__list[window.__list.length - 1];
    if (!last || last[0] !== n) window.__list.push([n, performance.now()]);
  }).observe(document, { childList: true, subtree: true });
})();"""
# Where the open time went, in ms after navigation started.
OPENING = """(n) => {
  const nav = performance.getEntriesByType("navigation")[0];
  const api = performance.getEntriesByType("resource")
    .find((r) => r.name.includes("/gui/api/fleet/"));
  const drawn = window.__list.find(([count]) => count >= n);
  return {
    "page HTML": nav.responseEnd,
    "page scripts run (DOMContentLoaded)": nav.domContentLoadedEventEnd,
    "fleet API asked": api ? api.startTime : null,
    "fleet API answered": api ? api.responseEnd : null,
    "list drawn": drawn ? drawn[1] : null,
  };
}"""
QUERIES = """
from django.db import connection
from django.test.utils import CaptureQueriesContext
from rosbridge_app.selectors.fleet import fleet
with CaptureQueriesContext(connection) as queries:
    vehicles = fleet()
print("QUERIES", len(queries.captured_queries), len(vehicles))
"""
# Notes when each vehicle's entry in the fleet list shows a new mode (epoch ms):
# the DOM changed, and the next animation frame (the change is painted with it).
OBSERVE = """() => {
  window.__modes = [];
  const shown = new Map();
  const list = document.querySelector("#fleet-list");
  const note = () => {
    const at = performance.timeOrigin + performance.now();
    for (const b of list.querySelectorAll(".fleet-vehicle")) {
      if (shown.get(b.dataset.vehicle) !== b.dataset.mode) {
        shown.set(b.dataset.vehicle, b.dataset.mode);
        const entry = [b.dataset.vehicle, b.dataset.mode, at, null];
        window.__modes.push(entry);
        requestAnimationFrame(() => (entry[3] = performance.timeOrigin + performance.now()));
      }
    }
  };
  new MutationObserver(note).observe(list, { childList: true, subtree: true, attributes: true });
  note();
}"""


def open_fleet(page, url: str, n: int) -> tuple[float, dict]:
    """Seconds until the fleet list shows ``n`` vehicles, and where they went."""
    opened = time.monotonic()
    # Timed to the list, not to the page's load event.
    page.goto(f"{url}/?view=fleet", wait_until="commit")
    page.wait_for_function("(n) => document.querySelectorAll('.fleet-vehicle').length >= n", arg=n)
    return time.monotonic() - opened, page.evaluate(OPENING, n)


def answer(out: str, tag: str) -> str:
    """What a Django shell run printed after ``tag`` on its line."""
    return next(x for x in out.splitlines() if x.startswith(tag + " "))[len(tag) + 1 :]


def pct(values, q):
    values = sorted(values)
    return values[max(0, round(len(values) * q) - 1)] if values else float("nan")


def descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        todo += children.get(p, [])
    return found


def usage(pids) -> tuple[float, float]:
    """CPU seconds and RSS (MB) of ``pids`` now."""
    cpu = rss = 0.0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
            cpu += (int(fields[11]) + int(fields[12])) / TICK
            rss += int(fields[21]) * os.sysconf("SC_PAGE_SIZE") / 1e6
        except (OSError, IndexError, ValueError):
            pass
    return cpu, rss


def run(n: int, args) -> dict:
    import requests
    from playwright.sync_api import sync_playwright

    from rosbridge_app.collector import params as P

    work = Path(tempfile.mkdtemp(prefix=f"ftt-fleet{n}-"))
    url = fresh_database(args.database_url, f"fleet{n}")
    server = Server(work, "", url, name=f"fleet-bench-{n}")
    server.workers = 2
    # The live link's and the collectors' timings of each switch (stages()).
    server.env["DJANGO_SETTINGS_MODULE"] = "benchmarks.fleet_settings"
    if args.redis_url:
        server.env["FTT_REDIS_URL"] = args.redis_url
    server.start()
    procs: dict[str, list[subprocess.Popen]] = {"collector": [], "robot": []}
    try:
        out = server.python(session_code("director", "viewer") + SETUP.format(n=n))
        key, legs = answer(out, "SETUP").split(" ", 1)
        legs = json.loads(legs)
        defaults = P.read_file(P.DEFAULT_FILE)
        for i in range(n):
            env = {**server.env, "ROS_DOMAIN_ID": str(args.domain + i)}
            env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
            values = dict(defaults, vehicle=f"fleet-{i}")
            values["params.pose_min_distance"] = values["params.pose_min_period"] = 0.0
            P.write_file(work / f"c{i}.yaml", values)
            log = open(work / f"collector{i}.log", "wb")
            procs["collector"].append(
                subprocess.Popen(
                    [sys.executable, "manage.py", "ftt_collect", "--params-file"]
                    + [str(work / f"c{i}.yaml"), "--name", f"fleet-{i}", "--start-logging"]
                    + ["--spool", str(work / f"spool{i}.sqlite3")],
                    cwd=ROOT,
                    env=env,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                )
            )
            procs["robot"].append(
                subprocess.Popen(
                    [sys.executable, "manage.py", "ftt_simulate", "--switch-every"]
                    + [str(args.switch_every), "--gps-rate", "10", "--tf-rate", "10"]
                    + ["--camera-rate", "1", "--camera-size", "320x240", "--map-size", "40"]
                    # A little longer than --seconds: the switch at --seconds is published
                    # (the mode goes out once a second).
                    + ["--duration", str(args.seconds + 1.5), "--wait-for-subscriber", "120"]
                    + ["--latitude", str(50.6160 + i * 0.0005)],
                    cwd=ROOT,
                    env=env,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.STDOUT,
                    text=True,
                    preexec_fn=(lambda: os.nice(args.robot_nice)) if args.robot_nice else None,
                )
            )
        with sync_playwright() as pw:
            chromium = os.environ.get("FTT_CHROMIUM") or system_chromium()
            browser = pw.chromium.launch(**({"executable_path": chromium} if chromium else {}))
            context = browser.new_context(viewport={"width": 1366, "height": 768})
            context.add_cookies([{"name": "sessionid", "value": key, "url": server.url}])
            context.add_init_script(FRAMES)
            page = context.new_page()
            # Once every robot logs, the fleet view is opened and timed.
            deadline = time.monotonic() + 150
            while time.monotonic() < deadline:
                api = requests.get(f"{server.url}/gui/api/fleet/", cookies={"sessionid": key})
                if len([v for v in api.json()["vehicles"] if v["position"]]) == n:
                    break
                time.sleep(1)
            open_s, opening = open_fleet(page, server.url, n)
            # Again, as a director who had it open before would: the cache is warm.
            _, warm = open_fleet(page, server.url, n)
            opening["list drawn, opened again"] = warm["list drawn"]
            page.evaluate(OBSERVE)
            # A switch before this was on screen before the page watched: not timed.
            watched = time.time()
            queries = server.python(QUERIES)
            queries = answer(queries, "QUERIES").split()
            queries = f"{queries[0]} for {queries[1]} vehicles"
            api_times = []
            pids = {
                "server": descendants(server.process.pid) + [server.worker.pid],
                "collectors": [p.pid for p in procs["collector"]],
                "robots (simulators)": [p.pid for p in procs["robot"]],
            }
            # Playwright's driver and Chromium: this process's other descendants.
            ours = {pid for group in pids.values() for pid in group}
            pids["browser"] = [p for p in descendants(os.getpid())[1:] if p not in ours]
            before = {kind: usage(p) for kind, p in pids.items()}
            t_start = time.monotonic()
            rss_max = dict.fromkeys(pids, 0.0)
            cpu = dict.fromkeys(pids, 0.0)
            # Sampled while every robot still runs (an ended process has no CPU time left).
            while all(p.poll() is None for p in procs["robot"]):
                t = time.monotonic()
                requests.get(f"{server.url}/gui/api/fleet/", cookies={"sessionid": key})
                api_times.append(time.monotonic() - t)
                for kind, p in pids.items():
                    seconds, rss = usage(p)
                    rss_max[kind] = max(rss_max[kind], rss)
                    cpu[kind] = (seconds - before[kind][0]) / (time.monotonic() - t_start)
                time.sleep(2)
            for p in procs["robot"]:
                p.wait(60)
            # The switches still on their way (spooled, or not yet shown) get there
            # before anything is counted, within a deadline.
            expected = int(args.seconds // args.switch_every) + 1  # + the first master
            deadline = time.monotonic() + args.drain
            while time.monotonic() < deadline:
                counts = json.loads(answer(server.python(COUNT.format(legs=legs)), "COUNT"))
                if all(counts.get(str(leg), 0) >= expected for leg in legs):
                    break
                time.sleep(2)
            drained = args.drain - max(0.0, deadline - time.monotonic())
            time.sleep(2)  # the last switches' frames reach the page
            shown = page.evaluate("window.__modes")
            frames = page.evaluate("window.__frames")
            browser.close()
        starts, published = [], []
        for p in procs["robot"]:
            text = p.stdout.read()
            starts.append(float(text.split("started at ")[1].split(";")[0]))
            published.append(json.loads(text.split("published ")[1].strip().replace("'", '"')))
        for p in procs["collector"]:
            p.send_signal(2)
        for p in procs["collector"]:
            p.wait(60)
        left = [(work / f"collector{i}.log").read_text(errors="replace") for i in range(n)]
        left = [line for text in left for line in text.splitlines() if "stay in" in line]
        results = server.python(RESULTS.format(legs=legs))
        results = json.loads(answer(results, "RESULTS"))
        vehicles = json.loads(
            server.python(
                "import json\nfrom events.models import Vehicle\n"
                "print(json.dumps({v.key: v.pk for v in Vehicle.objects.all()}))"
            ).splitlines()[-1]
        )
    finally:
        for kind in procs.values():
            for p in kind:
                if p.poll() is None:
                    p.kill()
        server.stop()
        errors = (ARTIFACTS / f"fleet-bench-{n}.log").read_text(errors="replace")
        drop_database(url)
    logs = [(work / f"collector{i}.log").read_text(errors="replace") for i in range(n)]
    timing = stages(args, legs, starts, results, vehicles, shown, frames, errors, logs, watched)
    return summarise(n, args, legs, starts, published, results, vehicles, shown, watched) | {
        "stages": timing,
        "drained_s": drained,
        "left_in_spool": left,
        "opening": opening,
        "open_queries": queries,
        "open_s": open_s,
        "api_p95": pct(api_times, 0.95),
        "cpu": cpu,
        "rss": rss_max,
        "errors": errors.count("Traceback") + errors.count(" ERROR "),
        "load": os.getloadavg()[0],
    }


STAGES = [
    ("robot: switch -> mode published (1 Hz)", "switch", "published"),
    ("DDS: published -> collector received", "published", "received"),
    ("collector: received -> segment row written", "received", "written"),
    ("written -> NOTIFY heard by the web worker", "written", "notified"),
    ("written -> read by the live poller", "written", "read"),
    ("server: read -> frame sent", "read", "sent"),
    ("sent -> message in the page", "sent", "message"),
    ("page: message -> list updated", "message", "shown"),
    ("page: list updated -> next frame", "shown", "painted"),
    ("server + browser: written -> next frame", "written", "painted"),
    ("FTT: published -> next frame", "published", "painted"),
    ("switch -> next frame", "switch", "painted"),
]
LIVE = re.compile(r"live (read|sent) segments=\[([\d, ]*)\] at=([\d.]+)(?: notified=([\d.]+))?")
RECEIVED = re.compile(r"mode \S+ start=([\d.]+) received=([\d.]+)")


def stages(args, legs, starts, results, vehicles, shown, frames, server_log, logs, watched):
    """Per stage of a switch's way to the screen, the seconds each switch spent in it."""
    read, sent, notified = {}, {}, {}
    for step, ids, at, heard in LIVE.findall(server_log):
        for row in map(int, filter(None, ids.split(","))):
            (read if step == "read" else sent).setdefault(row, float(at))
            if step == "read" and heard:
                notified.setdefault(row, float(heard))
    message = {}
    for ids, at in frames:
        for row in ids:
            message.setdefault(row, at / 1000)
    spans = {label: [] for label, _, _ in STAGES}
    for i, leg in enumerate(legs):
        received = {round(float(s), 3): float(r) for s, r in RECEIVED.findall(logs[i])}
        vehicle = vehicles[f"fleet-{i}"]
        for mode, start, _bound, row, written in results[str(leg)]["masters"][1:]:
            k = round((start - starts[i]) / args.switch_every)
            t = {"switch": starts[i] + k * args.switch_every, "published": start}
            if t["switch"] < watched:
                continue
            t["received"] = received.get(round(start, 3))
            t["written"], t["read"], t["sent"] = written, read.get(row), sent.get(row)
            # A NOTIFY heard before the row was written woke nobody for it (a poll did).
            heard = notified.get(row)
            t["notified"] = heard if heard and written and heard >= written else None
            t["message"] = message.get(row)
            later = [
                (at / 1000, painted / 1000 if painted else None)
                for v, m, at, painted in shown
                if int(v) == vehicle and m == mode and at / 1000 >= t["switch"]
            ]
            t["shown"], t["painted"] = min(later) if later else (None, None)
            for label, a, b in STAGES:
                if t[a] is not None and t[b] is not None:
                    spans[label].append(t[b] - t[a])
    return spans


def summarise(n, args, legs, starts, published, results, vehicles, shown, watched) -> dict:
    errors, bounds, screen, stored, expected, stored_after = [], [], [], 0, 0, []
    missing_pub = missing_stored = estimated = 0
    for i, leg in enumerate(legs):
        r = results[str(leg)]
        t0, every = starts[i], args.switch_every
        masters = r["masters"][1:]  # the first one opened when logging started
        expected += int(args.seconds // every)
        stored += len(masters)
        for mode, start, uncertainty, _row, modified in masters:
            k = round((start - t0) / every)
            if modified is not None:
                stored_after.append(modified - (t0 + k * every))
            errors.append(abs(start - (t0 + k * every)))
            bounds.append(uncertainty or 0.0)
            vehicle = vehicles[f"fleet-{i}"]
            seen = [at / 1000 for v, m, at, _painted in shown if int(v) == vehicle and m == mode]
            later = [at for at in seen if at >= t0 + k * every]
            if later and t0 + k * every >= watched:
                screen.append(min(later) - (t0 + k * every))
        missing_pub += published[i]["gps"]
        missing_stored += r["poses"]
        estimated += r["missed"] or 0
    lost = max(0, missing_pub - missing_stored)
    return {
        "n": n,
        "switches": f"{stored}/{expected}",
        "error_max": max(errors, default=float("nan")),
        "errors_over_0_5": sum(e > 0.5 for e in errors),
        "errors_beyond_bound": sum(e > b + 0.05 for e, b in zip(errors, bounds, strict=True)),
        "bound_max": max(bounds, default=0.0),
        "fixes_missing": f"{lost} of {missing_pub} ({100 * lost / max(missing_pub, 1):.2f} %)",
        "estimated": estimated,
        "stored_p50": pct(stored_after, 0.5),
        "stored_p95": pct(stored_after, 0.95),
        "screen_p50": pct(screen, 0.5),
        "screen_p95": pct(screen, 0.95),
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--database-url", required=True)
    parser.add_argument("--redis-url", default="")
    parser.add_argument("--robots", type=int, nargs="+", default=[3, 6, 10])
    parser.add_argument("--seconds", type=float, default=150)
    parser.add_argument("--switch-every", type=float, default=10)
    parser.add_argument("--domain", type=int, default=90, help="robot i: ROS domain DOMAIN + i")
    parser.add_argument(
        "--drain",
        type=float,
        default=120,
        help="after the robots stop, wait up to this long for every switch to be stored",
    )
    parser.add_argument(
        "--robot-nice",
        type=int,
        default=0,
        help="run the simulated robots at this nice value (they stand for other computers)",
    )
    args = parser.parse_args()
    rows = [run(n, args) for n in args.robots]
    load = os.getloadavg()
    print(f"{os.cpu_count()} cores, load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}")
    keys = [
        ("switches stored / robot switches", "switches"),
        ("switch time error, max (s)", "error_max"),
        ("switch time errors > 0.5 s", "errors_over_0_5"),
        ("errors beyond the stored bound", "errors_beyond_bound"),
        ("largest stored uncertainty (s)", "bound_max"),
        ("GPS fixes missing", "fixes_missing"),
        ("fixes missed, collectors' estimate", "estimated"),
        ("switch -> stored p50 (s)", "stored_p50"),
        ("switch -> stored p95 (s)", "stored_p95"),
        ("switch -> fleet view p50 (s)", "screen_p50"),
        ("switch -> fleet view p95 (s)", "screen_p95"),
        ("fleet view open (s)", "open_s"),
        ("fleet API p95 (s)", "api_p95"),
        ("server errors logged", "errors"),
        ("load average (1 min) at the end", "load"),
        ("waited after the robots stopped (s)", "drained_s"),
        ("fleet selector's queries", "open_queries"),
    ]
    print("| | " + " | ".join(f"{r['n']} robots" for r in rows) + " |")
    print("|---|" + "---|" * len(rows))
    for label, key in keys:
        cells = [f"{r[key]:.3f}" if isinstance(r[key], float) else str(r[key]) for r in rows]
        print(f"| {label} | " + " | ".join(cells) + " |")
    for label, _, _ in STAGES:
        spans = [r["stages"][label] for r in rows]
        cells = [f"{pct(x, 0.5) * 1e3:.0f} / {pct(x, 0.95) * 1e3:.0f} ({len(x)})" for x in spans]
        print(f"| {label}, p50 / p95 ms (switches) | " + " | ".join(cells) + " |")
    for label in rows[0]["opening"]:
        cells = [f"{r['opening'][label] or float('nan'):.0f}" for r in rows]
        print(f"| open: {label}, ms after navigation | " + " | ".join(cells) + " |")
    for kind in rows[0]["cpu"]:
        cells = [f"{r['cpu'][kind] * 100:.0f} % / {r['rss'][kind]:.0f} MB" for r in rows]
        print(f"| CPU / RSS: {kind} | " + " | ".join(cells) + " |")
    print(
        "Robots' share (simulators + collectors, on the robots in a real fleet) vs the server's: "
        + "; ".join(
            f"{r['n']}: {100 * (r['cpu']['collectors'] + r['cpu']['robots (simulators)']):.0f} % "
            f"vs {100 * r['cpu']['server']:.0f} %"
            for r in rows
        )
    )
    for r in rows:
        for line in r["left_in_spool"]:
            print(f"{r['n']} robots, left in a spool at the end: {line}")


if __name__ == "__main__":
    main()
