"""How fast the REST API serves tracks and takes poses, on the configured database.

Builds a throw-away test event with one leg of N GPS poses (default 100 000) over
20 master segments, then times:
  * GET /api/tracks/?leg=ID (one LineString per master),
  * GET /gui/api/legs/ID/tracks/ whole and with ?zoom=16, gzipped (bytes printed),
  * GET /api/poses/?leg=ID&page_size=5000 (one page of rows),
  * POST /api/poses/batch/ with batches of 1 000 and 5 000 new poses, and each
    batch again (all known), in process; medians beside the target of 20 000/s,
  * POST /api/poses/ with one pose, in process with a token: the median time and
    the statements it sends (target: at most 2, in one transaction; BEGIN and
    COMMIT not counted).  This is the view; over HTTP the production server's
    pose route answers it before Django (ftt_site/inbound/pose_route.py), with the
    same code from the quick check on.
Everything is deleted afterwards.

With ``--clients 1,4,16`` it then starts a web server on loopback (``--server
production``, the default, is Gunicorn with 2 Uvicorn workers as scripts/run.sh
starts it; ``daphne`` and ``gunicorn`` with 2 sync workers for comparison) and
lets that many clients POST single poses to /api/poses/ for ``--seconds`` each;
the stored rows are counted in the database and must equal the answered requests.
Before them it posts the batches of 1 000 and 5 000 again, over HTTP.  With
``--robots N`` the single poses run a second time in the field's shape: N
robots, each its own vehicle, leg and open segment.

``--against PATH[=DATABASE_URL]`` (repeatable) measures other checkouts
after this one (e.g. 9f3f5ae and main in ``git worktree``s; 9f3f5ae on a
database migrated by its own code), then the original once, and prints all
figures side by side (docs/ingest.md has the command).  Every FTT run ends
with the figures recount (``ftt_recount_figures``).

``--original PATH`` (the original FTT's ``ftt_server/scripts/api.py``, from
github.com/fkie/field_test_tool) starts that server too, unchanged, as it ships
(Flask's threaded server) with ``--original-python`` (a venv with flask,
flask-restful, flask-cors, psycopg2, lxml), connected to ``--original-db`` (a
database made from its ftt_schema.sql and setup_queries.sql; docs/api.md, Speed).
It gets the same load on its ``/pose``; rows are counted in its database, and
the ratios are printed against the target: at least the original's poses/s.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/api_throughput.py [--poses N]
        [--clients 1,4,16 --seconds 10] [--original .../ftt_server/scripts/api.py
         --original-python /work/orig-venv/bin/python --original-db postgresql://...]
"""

import argparse
import gc
import http.client
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import threading
import time
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

# ``--tree PATH`` measures another checkout's code (e.g. main's, in a ``git
# worktree``) with this file's measurements; ``--against PATH`` runs that after
# this tree, in the same run, and prints both side by side.
ROOT = Path(__file__).resolve().parent.parent
if "--tree" in sys.argv:
    ROOT = Path(sys.argv[sys.argv.index("--tree") + 1]).resolve()
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

from django.contrib.auth import get_user_model  # noqa: E402
from django.contrib.auth.models import Group  # noqa: E402
from django.db import connection  # noqa: E402
from django.test.utils import CaptureQueriesContext  # noqa: E402
from rest_framework.authtoken.models import Token  # noqa: E402
from rest_framework.test import APIClient  # noqa: E402

from events.models import Segment, Vehicle  # noqa: E402
from events.services import deletion, logs, segments  # noqa: E402
from telemetry.models import Pose  # noqa: E402

# A tree from before the stored figures (9f3f5ae) stores poses in
# telemetry.services.recording and has no recount.
try:
    from telemetry.services import pose_writes  # noqa: E402
    from telemetry.services.segment_figures import recount_figures  # noqa: E402
except ImportError:
    from telemetry.services import recording as pose_writes  # noqa: E402

    recount_figures = None
GpsFix = pose_writes.GpsFix

SEGMENTS = 20
# The figures --against compares, by name.
SUMMARY: dict[str, float] = {}


def timed(label, func, rows=None):
    start = time.perf_counter()
    result = func()
    seconds = time.perf_counter() - start
    rate = f", {rows / seconds:,.0f} rows/s" if rows else ""
    print(f"{label:<48} {seconds:8.3f} s{rate}")
    return result


TARGET_RATIO = 1.0
BATCH_TARGET = 20_000  # poses/s through POST /api/poses/batch/ on PostGIS
SINGLE_QUERIES_TARGET = 2  # statements of one stored pose, in one transaction (issue 44)


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
    # A session of its own: the original's debug reloader runs the server in a
    # child process, which must go down with it.
    process = subprocess.Popen(
        command,
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    wait_for(port, process)
    return process


def stop(process):
    os.killpg(process.pid, signal.SIGTERM)
    process.wait()


def ftt_server(kind, port, workers):
    env = os.environ.copy()
    # The per-client request rate (3000/min by default, counted per process) would
    # answer 429 to a quiet run's 16 clients; the original has no such limit.
    # Counted per second: DRF keeps every request's time within the window in the
    # cache and unpickles and pickles the whole list on every request, so a
    # minute of 700 requests/s (42 000 times) cost 1.8 ms of CPU per request,
    # more than the rest of a lean pose.  The configured 3000/min keeps it
    # below 3 000 times (0.08 ms); a second of this run below 1 000.
    env["FTT_API_RATE_USER"] = "1000000/s"
    if kind == "production":
        # What scripts/run.sh starts: Gunicorn supervising Uvicorn workers.
        env["FTT_WEB_WORKERS"] = str(workers)
        config = "ftt_site/server/gunicorn.conf.py"
        if not (ROOT / config).exists():
            config = "ftt_site/gunicorn.conf.py"  # where older trees have it
        command = [
            *("gunicorn", "-c", config, "-b", f"127.0.0.1:{port}"),
            "ftt_site.asgi:application",
        ]
    elif kind == "gunicorn":
        # A long timeout: on a busy machine the first request (imports) can exceed 30 s.
        command = ["gunicorn", "-w", "2", "-t", "300", "-b", f"127.0.0.1:{port}", "ftt_site.wsgi"]
    else:
        command = ["daphne", "-b", "127.0.0.1", "-p", str(port), "ftt_site.asgi:application"]
    bin_dir = Path(sys.executable).parent
    return start([str(bin_dir / command[0]), *command[1:]], port, env=env)


# The original's api.py connects to dbname 'ftt' as postgres/postgres, fixed in
# its code.  Its code is run unchanged; only psycopg2.connect is pointed at the
# database given (argv[1]) before api.py runs as __main__.
ORIGINAL_LAUNCHER = """
import runpy, sys
import psycopg2
dsn, path = sys.argv[1], sys.argv[2]
connect = psycopg2.connect
psycopg2.connect = lambda *args, **kwargs: connect(dsn)
sys.argv = [path, *sys.argv[3:]]
runpy.run_path(path, run_name="__main__")
"""


def psql(dsn, query) -> str:
    out = subprocess.run(["psql", dsn, "-Atqc", query], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def prepare_original(dsn) -> None:
    """An open master segment to post to, as the original's GUI would leave it
    (its schema seeds no pose source, though its ROS node sends id 1)."""
    psql(
        dsn,
        """
        INSERT INTO pose_source (id, key, short_description) VALUES (1, 'gps', 'GPS')
            ON CONFLICT DO NOTHING;
        WITH e AS (INSERT INTO test_event (starttime_secs, location)
                   VALUES (extract(epoch FROM now()), 'benchmark') RETURNING id),
             s AS (INSERT INTO shift (test_event_id, starttime_secs, number)
                   SELECT id, extract(epoch FROM now()), 1 FROM e RETURNING id),
             l AS (INSERT INTO leg (shift_id, starttime_secs, number, default_pose_source_id)
                   SELECT id, extract(epoch FROM now()), 1, 1 FROM s RETURNING id)
        INSERT INTO segment (leg_id, segment_type_id, starttime_secs)
            SELECT id, 2, extract(epoch FROM now()) FROM l;
        """,
    )


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

    threads = [
        threading.Thread(target=client, args=(i,), name=f"client-{i}") for i in range(clients)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if failures:
        print(f"  {len(failures)} requests failed, e.g. {failures[0]}")
    return sum(answered)


def original_rows(dsn) -> int:
    return int(psql(dsn, "SELECT count(*) FROM pose"))


def robot_masters(event, t0, count) -> list:
    """The field's shape: ``count`` robots, each its own vehicle, shift, leg and
    open master segment."""
    masters = []
    for i in range(count):
        vehicle, _ = Vehicle.objects.get_or_create(key=f"bench-robot-{i}", short_description="b")
        shift = logs.create_shift(test_event=event, vehicle=vehicle, at=t0)
        leg = logs.create_leg(shift=shift, at=t0)
        masters.append(segments.report_mode(leg, "auto", at=t0 + timedelta(seconds=1)).master)
    return masters


# The original's rates ({clients: stored poses/s}), measured once per run: it
# has one open segment its robot writes to ("Current Segment", as its ROS node
# sends), so both shapes are compared with the same figures.
ORIGINAL = None


def original_rates(args, counts) -> dict[int, float]:
    """The original FTT's stored poses/s at each count of clients, POSTing
    single poses to its ``/pose`` as its robot node does."""
    rates = {}
    prepare_original(args.original_db)
    port = free_port()
    launcher = [args.original_python, "-c", ORIGINAL_LAUNCHER, args.original_db]
    server_args = ["--server_ip", "127.0.0.1", "--server_port", str(port)]
    original = start([*launcher, args.original, *server_args], port)
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
        hammer(port, "/pose", original_body, plain, 2, 3)
        for clients in counts:
            before = original_rows(args.original_db)
            answered = hammer(port, "/pose", original_body, plain, clients, args.seconds)
            stored = original_rows(args.original_db) - before
            if stored != answered:
                # Its one connection, shared by the request threads, loses rows
                # (upstream's KNOWN_ISSUES); only stored rows count.
                print(f"  original, {clients} clients: {answered} answered, {stored} stored")
            rates[clients] = stored / args.seconds
            SUMMARY[f"original single/s {clients} clients"] = rates[clients]
    finally:
        stop(original)
    return rates


def concurrency(args, master, user, robots=None):
    """Single poses from N clients: into ``master`` (one segment), or with
    ``robots`` (masters) client i into robots[i % len]: a robot per segment."""
    global ORIGINAL
    counts = [int(c) for c in args.clients.split(",")]
    token, _ = Token.objects.get_or_create(user=user)
    port = free_port()
    server = ftt_server(args.server, port, args.workers)
    headers = {"Content-Type": "application/json", "Authorization": f"Token {token.key}"}
    results = {}
    targets = robots or [master]
    shape = "one robot per segment" if robots else "all clients into one segment"
    try:
        # Each client thread picks its own segment (thread name -> index).
        def ftt_body():
            index = int(threading.current_thread().name.rsplit("-", 1)[-1])
            return {"segment": targets[index % len(targets)].pk, "longitude": 8.0, "latitude": 50.0}

        def count():
            return Pose.objects.filter(segment__in=targets).count()

        # The first requests import every view module; not counted.
        hammer(port, "/api/poses/", ftt_body, headers, 2, 3)
        if robots is None:
            batches_over_http(port, headers, master, args.batches)
        for clients in counts:
            before = count()
            answered = hammer(port, "/api/poses/", ftt_body, headers, clients, args.seconds)
            stored = count() - before
            # Every answered pose is stored once, and nothing unanswered is.
            assert stored == answered, (stored, answered)
            results[clients] = [stored / args.seconds]
            SUMMARY[f"single/s {clients} clients, {shape}"] = stored / args.seconds
    finally:
        stop(server)
    if args.original:
        if ORIGINAL is None:
            ORIGINAL = original_rates(args, counts)
        for clients in counts:
            results[clients].append(ORIGINAL[clients])
    load = os.getloadavg()[0]
    print(
        f"\nPOST single poses, {shape}, stored poses/s ({args.server} server, "
        f"{args.workers} workers, "
        f"{args.seconds:g} s per "
        f"concurrency, load average {load:.1f})"
    )
    print(f"{'clients':>8} {'FTT':>10} {'original':>10} {'ratio':>7} {'target':>7}")
    for clients, rates in results.items():
        if len(rates) == 2:
            ratio = f"{rates[0] / rates[1]:.2f}x" if rates[1] else "inf"
            print(
                f"{clients:>8} {rates[0]:>10.0f} {rates[1]:>10.0f} {ratio:>7} {TARGET_RATIO:>6.1f}x"
            )
        else:
            print(f"{clients:>8} {rates[0]:>10.0f} {'-':>10} {'-':>7} {TARGET_RATIO:>6.1f}x")


def batches(client, master, t0, rounds):
    """Batches of 1 000 and of 5 000 full poses (as the collector sends them), each
    posted twice: the second time every uid is known and nothing is stored."""
    print(f"POST /api/poses/batch/, median of {rounds}, poses/s (target {BATCH_TARGET:,})")
    sent = 0
    for size in (1000, 5000):
        new, known, cpu = [], [], []
        for _ in range(rounds):
            # Encoded before the clock starts: a robot's client does that, not FTT.
            text = batch_body(master, size, t0 + timedelta(seconds=sent))
            sent += size
            for stored, rates in ((size, new), (0, known)):
                begin, cpu_begin = time.perf_counter(), time.process_time()
                answer = client.post("/api/poses/batch/", text, content_type="application/json")
                rates.append(size / (time.perf_counter() - begin))
                if stored:
                    cpu.append(time.process_time() - cpu_begin)
                assert answer.json() == {"stored": stored}, answer.content[:200]
        SUMMARY[f"batch of {size}, new poses/s"] = statistics.median(new)
        # This process's CPU per new batch (the database's is not in it): on a
        # shared machine it moves less with the load than the rate does.
        SUMMARY[f"batch of {size}, new, Python CPU ms"] = statistics.median(cpu) * 1000
        print(
            f"  {size:>5} per batch: new {statistics.median(new):>8,.0f}"
            f"   known {statistics.median(known):>8,.0f}"
            f"   (new: {statistics.median(cpu) * 1000:.0f} ms of this process's CPU)"
            f"   (load average {os.getloadavg()[0]:.1f})"
        )


def batch_body(master, size, start) -> str:
    """A batch of ``size`` full poses (as the collector sends them), a second
    apart from ``start`` on, encoded (a robot's client does that, not FTT)."""
    poses = [
        {
            "uid": str(uuid.uuid4()),
            "longitude": 8.0,
            "latitude": 50.0 + i * 1e-6,
            "altitude": 120.0,
            "fix_status": 0,
            "horizontal_accuracy": 0.03,
            "robot_stamp": (start + timedelta(seconds=i)).isoformat(),
        }
        for i in range(size)
    ]
    return json.dumps({"segment": master.pk, "poses": poses})


def batches_over_http(port, headers, master, rounds):
    """New batches of 1 000 and 5 000 through the server (body upload, the
    server's parsing and its database connection included)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=300)
    # After the in-process batches.
    start = master.start + timedelta(days=12)
    try:
        for size in (1000, 5000):
            rates = []
            for _ in range(rounds):
                text = batch_body(master, size, start)
                start += timedelta(seconds=size)
                begin = time.perf_counter()
                conn.request("POST", "/api/poses/batch/", text, headers)
                answer = conn.getresponse()
                body = answer.read()
                rates.append(size / (time.perf_counter() - begin))
                assert json.loads(body) == {"stored": size}, body[:200]
            SUMMARY[f"batch of {size} over HTTP, new poses/s"] = statistics.median(rates)
            print(
                f"POST /api/poses/batch/ over HTTP, {size} per batch: new"
                f" {statistics.median(rates):,.0f} poses/s (load average {os.getloadavg()[0]:.1f})"
            )
    finally:
        conn.close()


def single_in_process(master, user, rounds=200):
    """One pose per request through the whole stack (token included), in process."""
    token, _ = Token.objects.get_or_create(user=user)
    client = APIClient(HTTP_HOST="localhost", HTTP_AUTHORIZATION=f"Token {token.key}")
    body = {"segment": master.pk, "longitude": 8.0, "latitude": 50.0}
    # The first request reads the token and the segment (kept afterwards).
    assert client.post("/api/poses/", body, format="json").status_code == 201
    times = []
    for _ in range(rounds):
        begin = time.perf_counter()
        answer = client.post("/api/poses/", body, format="json")
        times.append(time.perf_counter() - begin)
        assert answer.status_code == 201, answer.content[:200]
    with CaptureQueriesContext(connection) as captured:
        client.post("/api/poses/", body, format="json")
    statements = [q for q in captured if q["sql"] not in ("BEGIN", "COMMIT")]
    SUMMARY["one pose in process, ms"] = statistics.median(times) * 1000
    SUMMARY["one pose in process, statements"] = len(statements)
    print(
        f"POST /api/poses/ one pose, in process: median {statistics.median(times) * 1000:.1f} ms,"
        f" {len(statements)} statements in {len(captured) - len(statements)} BEGIN/COMMIT"
        f" (target <= {SINGLE_QUERIES_TARGET})"
        f"   (load average {os.getloadavg()[0]:.1f})"
    )


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--poses", type=int, default=100_000)
    parser.add_argument("--clients", help="e.g. 1,4,16: single-pose POSTs through a server")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--batches", type=int, default=5, help="rounds per batch size")
    parser.add_argument(
        "--server", choices=["production", "daphne", "gunicorn"], default="production"
    )
    parser.add_argument("--workers", type=int, default=2, help="Uvicorn workers (production)")
    parser.add_argument("--original", help="path of the original FTT's api.py")
    parser.add_argument(
        "--original-python",
        default=sys.executable,
        help="the interpreter with the original's Flask, flask-restful, flask-cors, psycopg2",
    )
    parser.add_argument("--original-db", help="the original's PostgreSQL, to count its rows")
    parser.add_argument(
        "--robots", type=int, default=0,
        help="with --clients: also N robots, each its own vehicle, leg and open segment",
    )  # fmt: skip
    parser.add_argument("--tree", help="measure this checkout's code instead (see ROOT)")
    parser.add_argument(
        "--against", action="append", default=[], metavar="PATH[=DATABASE_URL]",
        help="another checkout, measured after this one (repeatable); a tree whose "
        "migrations differ needs a database of its own, migrated by its code",
    )  # fmt: skip
    parser.add_argument("--summary", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.against:
        return against(args)
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
                pose_writes.store_poses(master, fixes)
            return master

        master = timed(f"build {n:,} poses via services", build, n)
        client = APIClient(HTTP_HOST="localhost")
        client.force_authenticate(user)
        # The first request imports every view module (reports pull in matplotlib); not timed.
        client.get("/api/tracks/")
        # As the production server does once loaded (ftt_site/server/gunicorn.conf.py).
        gc.freeze()

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
        batches(client, master, t0, args.batches)
        single_in_process(master, user)
        if args.clients:
            concurrency(args, master, user)
            if args.robots:
                concurrency(args, master, user, robot_masters(event, t0, args.robots))
        if recount_figures is None:
            print("ftt_recount_figures: this tree keeps no figures")
        else:
            masters = Segment.objects.filter(leg__shift__test_event=event).masters()
            differences = recount_figures(list(masters.values_list("pk", flat=True)))
            print(f"ftt_recount_figures: {len(differences)} segments differ {differences or ''}")
            SUMMARY["figures that differ after the run"] = len(differences)
    finally:
        timed("delete the test event", lambda: deletion.delete(event))
        user.delete()
        if args.summary:
            Path(args.summary).write_text(json.dumps(SUMMARY))


def against(args):
    """This tree, then each ``--against`` tree, each in a process of its own with
    the same arguments (and the database given with the tree), then the
    original once; their figures side by side, with each tree's single-pose
    rates over the original's."""
    import tempfile

    rest = list(sys.argv[1:])
    for option in ("--against", "--tree", "--original", "--original-python", "--original-db"):
        while option in rest:
            at = rest.index(option)
            del rest[at : at + 2]
    trees = [(ROOT, os.environ["FTT_DATABASE_URL"])]
    for given in args.against:
        path, _, database = given.partition("=")
        trees.append((Path(path).resolve(), database or os.environ["FTT_DATABASE_URL"]))
    figures = {}
    for tree, database in trees:
        with tempfile.NamedTemporaryFile(suffix=".json") as out:
            print(f"\n===== {tree}", flush=True)
            command = [sys.executable, __file__, *rest, "--tree", str(tree), "--summary", out.name]
            env = {**os.environ, "FTT_DATABASE_URL": database}
            subprocess.run(command, check=True, env=env)
            figures[tree.name] = json.loads(Path(out.name).read_text())
    if args.original and args.clients:
        print("\n===== the original FTT", flush=True)
        counts = [int(c) for c in args.clients.split(",")]
        original_rates(args, counts)
        figures["original"] = dict(SUMMARY)
        for tree in trees:
            mine = figures[tree[0].name]
            for name in list(mine):
                if name.startswith("single/s "):
                    clients = int(name.split()[1])
                    mine[f"  ratio to the original{name[8:]}"] = (
                        mine[name] / SUMMARY[f"original single/s {clients} clients"]
                    )
    names = list(dict.fromkeys(n for found in figures.values() for n in found))
    columns = list(figures)
    print(f"\n{'':<60}" + "".join(f"{c[:14]:>15}" for c in columns)
          + f"   (load {os.getloadavg()[0]:.1f})")  # fmt: skip
    for name in names:
        cells = []
        for column in columns:
            value = figures[column].get(name)
            shown = "-" if value is None else format(value, ",.2f" if "ratio" in name else ",.1f")
            cells.append(f"{shown:>15}")
        print(f"{name:<60}" + "".join(cells))


if __name__ == "__main__":
    main()
