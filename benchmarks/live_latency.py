"""Live-update latency: robot write in one process -> browser websocket of daphne.

Starts daphne on a fresh SpatiaLite file (no broker), subscribes a websocket
client to a leg, lets a separate process switch modes and store pose batches,
and prints how long each announcement took from the writer's commit to the
client.  Run: .venv/bin/python benchmarks/live_latency.py [--count 40]
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

from tests.support.browser import Server  # noqa: E402

SETUP = """
from django.contrib.auth.models import Group, User
from django.contrib.sessions.backends.db import SessionStore
from events.models import Vehicle
from events.services import logs
user = User.objects.create_user("bench", password="x")
user.groups.add(Group.objects.get(name="viewer"))
s = SessionStore()
s["_auth_user_id"] = str(user.pk)
s["_auth_user_backend"] = "django.contrib.auth.backends.ModelBackend"
s["_auth_user_hash"] = user.get_session_auth_hash()
s.create()
v = Vehicle.objects.create(key="bench", short_description="Bench")
e = logs.create_test_event()
leg = logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v))
print("SESSION", s.session_key, leg.pk)
"""

WRITER = """
import time
from events.models import Leg
from events.services import segments
from telemetry.services import recording
leg = Leg.objects.get(pk={leg})
for i in range({count}):
    time.sleep(0.1)
    if i % 2:
        segments.report_mode(leg, "ito")
        kind = "segment"
    else:
        master = segments.report_mode(leg, "auto").master
        recording.record_poses(master, [recording.GpsFix(7.0 + i * 1e-5, 50.0)] * 1)
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
        out = server.python(SETUP)
        _, key, leg = next(line for line in out.splitlines() if line.startswith("SESSION")).split()
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


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int, default=40)
    asyncio.run(main(parser.parse_args().count))
