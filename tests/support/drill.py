"""The concurrent-clients drill: the production web server and many API clients at once.

:class:`WebServer` starts the server the way README's production section does
(Gunicorn with Uvicorn workers) on loopback; :func:`run_drill` lets N clients
each post a note and then a mode report, R times, all at the same moment; and
:func:`stored` reads back what the database kept. Used by
``tests/ftt_site/test_concurrent_clients.py`` and ``benchmarks/api_concurrency.py``.
"""

import json
import os
import socket
import subprocess
import sys
import textwrap
import threading
import time
import uuid
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import requests

ROOT = Path(__file__).resolve().parents[2]

SETUP = """
import json
from django.contrib.auth.models import Group, User
from rest_framework.authtoken.models import Token
from events.models import Vehicle
from events.services import logs, segments
user, _ = User.objects.get_or_create(username="drill")
user.groups.add(Group.objects.get(name="operator"))
token, _ = Token.objects.get_or_create(user=user)
vehicle, _ = Vehicle.objects.get_or_create(key="drill", defaults={"short_description": "drill"})
event = logs.create_test_event(location="drill")
shift = logs.create_shift(test_event=event, vehicle=vehicle)
leg = logs.create_leg(shift=shift)
master = segments.report_mode(leg, "auto").master
print(json.dumps({"token": token.key, "leg": leg.pk, "segment": master.pk}))
"""

STORED = """
import json, sys
from events.models import Note, Segment
uids = json.loads(sys.stdin.read())
leg = {leg}
notes = Note.objects.filter(segment__leg_id=leg)
print(json.dumps({{
    "notes": notes.count(),
    "distinct_note_uids": notes.values("uid").distinct().count(),
    "posted_uids_stored": notes.filter(uid__in=uids).count(),
    "open_masters": Segment.objects.filter(
        leg_id=leg, parent__isnull=True, end__isnull=True
    ).count(),
}}))
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class WebServer:
    """``gunicorn -k uvicorn_worker.UvicornWorker`` as README's production section starts it."""

    def __init__(self, env: dict, workers: int = 1, log: Path | None = None):
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {k: v for k, v in os.environ.items() if not k.startswith("FTT_")}
        self.env.update(
            DJANGO_SETTINGS_MODULE="ftt_site.settings",
            FTT_ALLOWED_HOSTS="127.0.0.1,localhost",
            PYTHONPATH=str(ROOT),
            **env,
        )
        self.workers = workers
        self.log_path = log
        self.process = None

    def manage(self, *args, stdin: str | None = None, timeout=300) -> str:
        result = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=ROOT,
            env=self.env,
            input=stdin,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        assert result.returncode == 0, result.stderr[-3000:]
        return result.stdout

    def python(self, code: str, stdin: str | None = None) -> str:
        return self.manage("shell", "-c", textwrap.dedent(code), stdin=stdin)

    def start(self, migrate: bool = True):
        if migrate:
            self.manage("migrate", "--noinput")
        log = open(self.log_path or os.devnull, "w")  # noqa: SIM115 - open while it runs
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gunicorn",
                "-c",
                str(ROOT / "ftt_site" / "gunicorn.conf.py"),
                "--bind",
                f"127.0.0.1:{self.port}",
                "--workers",
                str(self.workers),
                "ftt_site.asgi:application",
            ],
            cwd=ROOT,
            env=self.env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError("the web server exited")
            try:
                if requests.get(f"{self.url}/login/", timeout=2).status_code == 200:
                    return self
            except requests.RequestException:
                pass
            time.sleep(0.3)
        raise RuntimeError("the web server did not start")

    def stop(self):
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def prepare(server: WebServer) -> dict:
    return json.loads(server.python(SETUP).strip().splitlines()[-1])


def run_drill(url: str, setup: dict, clients: int, rounds: int) -> dict:
    """Every client posts a note and a mode report ``rounds`` times, all starting together."""
    barrier = threading.Barrier(clients)
    headers = {"Authorization": f"Token {setup['token']}"}

    def client(number: int):
        session = requests.Session()
        session.headers.update(headers)
        results = []
        barrier.wait()
        for round_ in range(rounds):
            note_uid = str(uuid.uuid4())
            started = time.perf_counter()
            note = session.post(
                f"{url}/api/notes/",
                json={"uid": note_uid, "segment": setup["segment"], "text": f"c{number} r{round_}"},
                timeout=120,
            )
            results.append(("note", note, note_uid, time.perf_counter() - started))
            started = time.perf_counter()
            mode = session.post(
                f"{url}/api/legs/{setup['leg']}/mode/",
                json={"mode": "ito" if (number + round_) % 2 else "auto"},
                timeout=120,
            )
            results.append(("mode", mode, None, time.perf_counter() - started))
        return results

    started = time.perf_counter()
    with ThreadPoolExecutor(max_workers=clients) as pool:
        per_client = list(pool.map(client, range(clients)))
    seconds = time.perf_counter() - started
    flat = [r for results in per_client for r in results]
    statuses = Counter(response.status_code for _, response, _, _ in flat)
    refused = [r for r in flat if r[1].status_code >= 400]
    return {
        "requests": len(flat),
        "seconds": seconds,
        "statuses": dict(sorted(statuses.items())),
        "refused": len(refused),
        "refused_without_retry_after": sum(
            1 for _, response, _, _ in refused if "Retry-After" not in response.headers
        ),
        "refusal_details": Counter(response.json().get("detail") for _, response, _, _ in refused),
        "created_note_uids": [
            uid for kind, response, uid, _ in flat if kind == "note" and response.status_code == 201
        ],
        "latencies": sorted(latency for *_, latency in flat),
    }


def stored(server: WebServer, setup: dict, note_uids: list[str]) -> dict:
    out = server.python(STORED.format(leg=setup["leg"]), stdin=json.dumps(note_uids))
    return json.loads(out.strip().splitlines()[-1])
