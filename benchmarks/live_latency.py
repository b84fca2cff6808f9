"""Live-update latency, in two ways.

Default: robot write in one process -> browser websocket of the production
server.  Starts it as the browser tests do (tests/support/browser.py) on a
fresh SpatiaLite file (no broker), subscribes a websocket client
to a leg, lets a separate process switch modes and store pose batches, and
prints how long each announcement took from the writer's commit to the client.

``--robot``: the whole way, robot message -> row on the operator's screen.
An rclpy publisher in this process stamps the time it sends each mode switch;
``ftt_collect`` runs in its own process (shipped parameters, logging), the
production server serves the GUI, and headless Chromium shows the leg; a MutationObserver notes
when the segment table gains the new row.  ``--database-url postgis://...``
runs it on PostGIS (a database this script may fill), else on SpatiaLite.

    .venv/bin/python benchmarks/live_latency.py [--count 40]
    .venv/bin/python benchmarks/live_latency.py --robot [--count 30] [--database-url URL]
"""

import argparse
import asyncio
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import websockets

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.support.browser import Server, session_code  # noqa: E402

WRITER = """
import time
from events.models import Leg
from events.services import segments
from telemetry.services import pose_writes
leg = Leg.objects.get(pk={leg})
for i in range({count}):
    time.sleep(0.1)
    if i % 2:
        segments.report_mode(leg, "ito")
        kind = "segment"
    else:
        master = segments.report_mode(leg, "auto").master
        pose_writes.store_poses(master, [pose_writes.GpsFix(7.0 + i * 1e-5, 50.0)] * 1)
        kind = "poses"
    print("WROTE", kind, time.time(), flush=True)
"""


async def listen(url, cookie, leg, results):
    async with websockets.connect(
        url, additional_headers={"Cookie": cookie, "Origin": "http://127.0.0.1"}
    ) as ws:
        await ws.send(json.dumps({"type": "subscribe", "leg": leg}))
        while True:
            message = json.loads(await ws.recv())
            if message["type"] == "events":
                now = time.time()
                for event in message["events"]:
                    results.append((event["kind"], now))


async def main(count):
    server = Server(Path(tempfile.mkdtemp(prefix="ftt-bench-")), "")
    server.start()
    try:
        out = server.python(setup_code("writer"))
        line = next(x for x in out.splitlines() if x.startswith("SESSION"))
        _, key, _, _, leg = line.split()
        url = f"ws://127.0.0.1:{server.port}/ws/live/"
        received = []
        listener = asyncio.create_task(listen(url, f"sessionid={key}", int(leg), received))
        await asyncio.sleep(1.0)
        writer = await asyncio.create_subprocess_exec(
            sys.executable,
            "manage.py",
            "shell",
            "-c",
            WRITER.format(leg=leg, count=count),
            cwd=ROOT,
            env=server.env,
            stdout=asyncio.subprocess.PIPE,
        )
        wrote = []
        async for line in writer.stdout:
            if line.startswith(b"WROTE"):
                _, kind, at = line.decode().split()
                wrote.append((kind, float(at)))
        await writer.wait()
        await asyncio.sleep(2.0)
        listener.cancel()
    finally:
        server.stop()
    # Odd writes switch to ITO (one "segment" event), even ones switch back to
    # AUTO and store a pose batch ("segment" then "poses"): pair each write
    # with the first later arrival of its kind.
    delays, i = [], 0
    for kind, at in wrote:
        while i < len(received) and not (received[i][0] == kind and received[i][1] >= at):
            i += 1
        if i < len(received):
            delays.append(received[i][1] - at)
            i += 1
    delays.sort()
    print(f"writes {len(wrote)}, matched {len(delays)}")
    print(
        f"latency commit->websocket: median {statistics.median(delays) * 1000:.0f} ms, "
        f"p90 {delays[int(len(delays) * 0.9) - 1] * 1000:.0f} ms, max {delays[-1] * 1000:.0f} ms"
    )


SETUP = """
from events.models import Vehicle
from events.services import logs
v = Vehicle.objects.create(key="bench-{tag}", short_description="Bench")
e = logs.create_test_event(location="live latency")
shift = logs.create_shift(test_event=e, vehicle=v)
leg = logs.create_leg(shift=shift)
print("SESSION", s.session_key, e.pk, shift.pk, leg.pk)
"""


def setup_code(tag: str) -> str:
    return session_code(f"bench-{tag}", "viewer") + SETUP.format(tag=tag)


ROBOT_CLEANUP = """
from django.contrib.auth.models import User
from events.models import TestEvent, Vehicle
from events.services import deletion
deletion.delete(TestEvent.objects.get(pk={event}))
deletion.delete(Vehicle.objects.get(key="bench-{tag}"))
User.objects.filter(username="bench-{tag}").delete()
"""

# Notes the time at which the segment table reaches each row count.
OBSERVE = """() => {
  window.__rows = [];
  const body = document.querySelector("#segment-table tbody");
  const note = () => window.__rows.push([body.children.length, Date.now()]);
  new MutationObserver(note).observe(body, { childList: true });
  note();
}"""


def robot(count: int, database_url: str | None) -> None:
    import os
    import subprocess

    import rclpy
    from playwright.sync_api import sync_playwright
    from std_msgs.msg import Bool

    from rosbridge_app.collector import params as P
    from tests.support.browser import system_chromium

    os.environ["ROS_DOMAIN_ID"] = os.environ.get("FTT_ROS_DOMAIN_ID") or str(60 + os.getpid() % 20)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    tag = str(os.getpid())
    work = Path(tempfile.mkdtemp(prefix="ftt-bench-"))
    server = Server(work, "")
    if database_url:
        server.env["FTT_DATABASE_URL"] = database_url
    server.env.update(
        ROS_DOMAIN_ID=os.environ["ROS_DOMAIN_ID"], ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST"
    )
    server.start()
    collector = None
    event = None
    try:
        out = server.python(setup_code(tag))
        line = next(x for x in out.splitlines() if x.startswith("SESSION"))
        _, key, event, shift, leg = line.split()
        values = P.read_file(P.DEFAULT_FILE)
        values["vehicle"] = f"bench-{tag}"
        P.write_file(work / "params.yaml", values)
        collector = subprocess.Popen(
            [sys.executable, "manage.py", "ftt_collect", "--params-file", str(work / "params.yaml")]
            + ["--name", f"bench-{tag}", "--spool", str(work / "spool.sqlite3")]
            + ["--start-logging"],
            cwd=ROOT,
            env=server.env,
            stdout=open(work / "collector.log", "wb"),
            stderr=subprocess.STDOUT,
        )
        rclpy.init()
        node = rclpy.create_node("ftt_latency_robot")
        mode = node.create_publisher(Bool, "robot_mode", 10)
        deadline = time.monotonic() + 120
        while mode.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        delays = []
        with sync_playwright() as pw:
            executable = os.environ.get("FTT_CHROMIUM") or system_chromium()
            browser = pw.chromium.launch(**({"executable_path": executable} if executable else {}))
            context = browser.new_context(viewport={"width": 1366, "height": 768})
            context.add_cookies([{"name": "sessionid", "value": key, "url": server.url}])
            page = context.new_page()
            page.goto(f"{server.url}/?event={event}&shift={shift}&leg={leg}")
            page.wait_for_selector("#live-status[data-state=ok]", timeout=60_000)
            page.wait_for_selector("#segment-table", state="attached")
            page.evaluate(OBSERVE)
            rows = 0
            for i in range(count + 1):
                sent = time.time()
                mode.publish(Bool(data=bool(i % 2)))
                page.wait_for_function(
                    "(n) => document.querySelectorAll('#segment-table tbody tr').length > n",
                    arg=rows,
                    timeout=30_000,
                    polling="raf",
                )
                notes = page.evaluate("window.__rows")
                shown = next(at for n, at in notes if n > rows)
                rows = max(n for n, _ in notes)
                if i:  # the first switch also waits for discovery: not counted
                    delays.append(shown / 1000 - sent)
                time.sleep(0.5)
            browser.close()
        node.destroy_node()
        rclpy.try_shutdown()
    finally:
        if collector is not None:
            collector.send_signal(2)
            collector.wait(60)
        if event is not None:
            server.python(ROBOT_CLEANUP.format(event=event, tag=tag))
        server.stop()
    delays.sort()
    load = os.getloadavg()
    print(
        f"database: {'PostGIS' if database_url else 'SpatiaLite'} · {os.cpu_count()} cores · "
        f"load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}"
    )
    print(
        f"robot mode message -> row on screen, n={len(delays)}: "
        f"median {statistics.median(delays) * 1000:.0f} ms, "
        f"p95 {delays[max(0, round(len(delays) * 0.95) - 1)] * 1000:.0f} ms, "
        f"max {delays[-1] * 1000:.0f} ms (target p95 <= 300 ms)"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--robot", action="store_true")
    parser.add_argument("--database-url")
    args = parser.parse_args()
    if args.robot:
        robot(args.count, args.database_url)
    else:
        asyncio.run(main(args.count))
