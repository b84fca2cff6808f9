"""The concurrent-clients drill: the production web server and many API clients at once.

:class:`~tests.support.web.WebServer` starts the production server on loopback;
:func:`run_drill` lets N clients each post a note and then a mode report, R
times, all at the same moment; and :func:`stored` reads back what the database
kept. Used by ``tests/ftt_site/test_concurrent_clients.py`` and
``benchmarks/api_concurrency.py``.
"""

import json
import threading
import time
import uuid
from collections import Counter
from concurrent.futures import ThreadPoolExecutor

import requests

from tests.support.web import WebServer

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
