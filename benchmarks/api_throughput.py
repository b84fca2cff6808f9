"""How fast the REST API serves tracks and takes pose batches, on the configured database.

Builds a throw-away test event with one leg of N GPS poses (default 100 000) over
20 master segments, then times:
  * GET /api/tracks/?leg=ID (one LineString per master),
  * GET /api/poses/?leg=ID&page_size=5000 (one page of rows),
  * GET /gui/api/legs/ID/tracks/ whole and with ?zoom=16, gzipped (bytes printed),
  * POST /api/poses/batch/ with 1000 new poses, and the same batch again (all known).
Everything is deleted afterwards. Prints seconds and rates.

With ``--clients 1,4,16`` it then starts a web server on loopback (``--server
daphne`` or ``gunicorn``, 2 sync workers) and lets that many clients POST single
poses to /api/poses/ for ``--seconds`` each; the stored rows are counted in the
database.  ``--original PATH`` (the original FTT's ``ftt_server/scripts/api.py``)
starts that server too, posts the same load to its ``/pose`` and counts rows in
``--original-db`` (its PostgreSQL, with an open master segment), then prints the
ratios against the target of 3x.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/api_throughput.py [--poses N]
        [--clients 1,4,16 --seconds 10 --server gunicorn]
        [--original .../ftt_server/scripts/api.py --original-db postgresql://...]
"""

import argparse
import http.client
import json
import os
import socket
import subprocess
import sys
import threading
import time
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

from django.contrib.auth import get_user_model  # noqa: E402
from django.contrib.auth.models import Group  # noqa: E402
from rest_framework.authtoken.models import Token  # noqa: E402
from rest_framework.test import APIClient  # noqa: E402

from events.models import Vehicle  # noqa: E402
from events.services import deletion, logs, segments  # noqa: E402
from telemetry.models import Pose  # noqa: E402
from telemetry.services import recording  # noqa: E402
from telemetry.services.recording import GpsFix  # noqa: E402

SEGMENTS = 20


def timed(label, func, rows=None):
    start = time.perf_counter()
    result = func()
    seconds = time.perf_counter() - start
    rate = f", {rows / seconds:,.0f} rows/s" if rows else ""
    print(f"{label:<48} {seconds:8.3f} s{rate}")
    return result


TARGET_RATIO = 3.0


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_for(port, process, seconds=60):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise SystemExit(f"the server exited with {process.returncode}")
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            time.sleep(0.2)
    raise SystemExit("the server did not start")


def start(command, port, env=None):
    process = subprocess.Popen(
        command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    wait_for(port, process)
    return process


def ftt_server(kind, port):
    if kind == "gunicorn":
        # A long timeout: on a busy machine the first request (imports) can exceed 30 s.
        command = ["gunicorn", "-w", "2", "-t", "300", "-b", f"127.0.0.1:{port}", "ftt_site.wsgi"]
    else:
        command = ["daphne", "-b", "127.0.0.1", "-p", str(port), "ftt_site.asgi:application"]
    bin_dir = Path(sys.executable).parent
    return start([str(bin_dir / command[0]), *command[1:]], port, env=os.environ.copy())


def hammer(port, path, body_for, headers, clients, seconds) -> int:
    """``clients`` threads POST one pose each, back to back, on kept-alive connections."""
    stop = time.monotonic() + seconds
    answered = [0] * clients
    failures = []

    def client(index):
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=300)
        while time.monotonic() < stop:
            try:
                conn.request("POST", path, json.dumps(body_for()), headers)
                response = conn.getresponse()
                response.read()
            except OSError as error:
                failures.append(repr(error))
                conn.close()
                continue
            if response.status >= 300:
                failures.append(f"HTTP {response.status}")
            else:
                answered[index] += 1
        conn.close()

    threads = [threading.Thread(target=client, args=(i,)) for i in range(clients)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if failures:
        print(f"  {len(failures)} requests failed, e.g. {failures[0]}")
    return sum(answered)


def original_rows(dsn) -> int:
    out = subprocess.run(
        ["psql", dsn, "-Atc", "SELECT count(*) FROM pose"], capture_output=True, text=True
    )
    return int(out.stdout.strip())


def concurrency(args, master, user):
    counts = [int(c) for c in args.clients.split(",")]
    token, _ = Token.objects.get_or_create(user=user)
    port = free_port()
    server = ftt_server(args.server, port)
    headers = {"Content-Type": "application/json", "Authorization": f"Token {token.key}"}
    results = {}
    try:

        def ftt_body():
            return {"segment": master.pk, "longitude": 8.0, "latitude": 50.0}

        # The first requests import every view module; not counted.
        hammer(port, "/api/poses/", ftt_body, headers, 2, 3)
        for clients in counts:
            before = Pose.objects.filter(segment=master).count()
            answered = hammer(port, "/api/poses/", ftt_body, headers, clients, args.seconds)
            stored = Pose.objects.filter(segment=master).count() - before
            assert stored == answered, (stored, answered)
            results[clients] = [stored / args.seconds]
    finally:
        server.terminate()
        server.wait()
    if args.original:
        port = free_port()
        original = start(
            [sys.executable, args.original, "--server_ip", "127.0.0.1", "--server_port", str(port)],
            port,
        )
        try:

            def original_body():
                return {
                    "segment_id": "Current Segment",
                    "lat": 50.0,
                    "lng": 8.0,
                    "pose_source_id": 1,
                    "orig_secs": time.time(),
                }

            plain = {"Content-Type": "application/json"}
            for clients in counts:
                before = original_rows(args.original_db)
                answered = hammer(port, "/pose", original_body, plain, clients, args.seconds)
                stored = original_rows(args.original_db) - before
                assert stored == answered, (stored, answered)
                results[clients].append(stored / args.seconds)
        finally:
            original.terminate()
            original.wait()
    print(f"\nPOST /api/poses/ single pose, stored poses/s ({args.server}, {args.seconds} s each)")
    print(f"{'clients':>8} {'FTT':>10} {'original':>10} {'ratio':>7} {'target':>7}")
    for clients, rates in results.items():
        if len(rates) == 2:
            ratio = f"{rates[0] / rates[1]:.2f}x"
            print(
                f"{clients:>8} {rates[0]:>10.0f} {rates[1]:>10.0f} {ratio:>7} {TARGET_RATIO:>6.1f}x"
            )
        else:
            print(f"{clients:>8} {rates[0]:>10.0f} {'-':>10} {'-':>7} {TARGET_RATIO:>6.1f}x")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--poses", type=int, default=100_000)
    parser.add_argument("--clients", help="e.g. 1,4,16: single-pose POSTs through a server")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--server", choices=["daphne", "gunicorn"], default="daphne")
    parser.add_argument("--original", help="path of the original FTT's api.py")
    parser.add_argument("--original-db", help="the original's PostgreSQL, to count its rows")
    args = parser.parse_args()
    if args.original and not args.original_db:
        parser.error("--original needs --original-db")
    n = args.poses
    t0 = datetime(2026, 1, 5, 8, tzinfo=UTC)
    vehicle, _ = Vehicle.objects.get_or_create(key="bench-api", short_description="bench")
    user, _ = get_user_model().objects.get_or_create(username="bench-api-operator")
    user.groups.add(Group.objects.get(name="operator"))
    event = logs.create_test_event(at=t0, location="api benchmark")
    try:
        shift = logs.create_shift(test_event=event, vehicle=vehicle, at=t0)
        leg = logs.create_leg(shift=shift, at=t0)
        per = n // SEGMENTS

        def build():
            for s in range(SEGMENTS):
                at = t0 + timedelta(seconds=1 + s * per)
                master = segments.report_mode(leg, ("auto", "ito")[s % 2], at=at).master
                fixes = [
                    GpsFix(7.0 + i * 1e-6, 50.0 + s * 1e-3, robot_stamp=at + timedelta(seconds=i))
                    for i in range(per)
                ]
                recording.record_poses(master, fixes)
            return master

        master = timed(f"build {n:,} poses via services", build, n)
        client = APIClient(HTTP_HOST="localhost")
        client.force_authenticate(user)
        # The first request imports every view module (reports pull in matplotlib); not timed.
        client.get("/api/tracks/")

        tracks = timed(
            "GET /api/tracks/?leg", lambda: client.get("/api/tracks/", {"leg": leg.pk}), n
        )
        assert tracks.status_code == 200 and len(tracks.json()["features"]) == SEGMENTS
        print(f"{'  response size':<48} {len(tracks.content) / 1e6:8.2f} MB")
        for label, query in (("all points", ""), ("?zoom=16", "?zoom=16")):
            url = f"/gui/api/legs/{leg.pk}/tracks/{query}"
            gui = timed(
                f"GET /gui/api/legs/ID/tracks/ {label}, gzip",
                lambda url=url: client.get(url, HTTP_ACCEPT_ENCODING="gzip"),
                n,
            )
            assert gui.status_code == 200 and gui["Content-Encoding"] == "gzip"
            print(f"{'  bytes sent':<48} {len(gui.content) / 1e3:8.1f} kB")
        page = timed(
            "GET /api/poses/?leg&page_size=5000",
            lambda: client.get("/api/poses/", {"leg": leg.pk, "page_size": 5000}),
            5000,
        )
        assert page.status_code == 200
        batch = {
            "segment": master.pk,
            "poses": [
                {"uid": str(uuid.uuid4()), "longitude": 8.0, "latitude": 50.0 + i * 1e-6}
                for i in range(1000)
            ],
        }
        post = lambda: client.post("/api/poses/batch/", batch, format="json")  # noqa: E731
        first = timed("POST /api/poses/batch/ (1000 new)", post, 1000)
        again = timed("POST /api/poses/batch/ (1000 known)", post, 1000)
        assert first.json() == {"stored": 1000} and again.json() == {"stored": 0}
        print(f"{'  target for new batches':<48} {'':8}   20,000 rows/s")
        if args.clients:
            concurrency(args, master, user)
    finally:
        timed("delete the test event", lambda: deletion.delete(event))
        user.delete()


if __name__ == "__main__":
    main()
