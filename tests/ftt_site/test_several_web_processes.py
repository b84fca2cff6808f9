"""A change committed in one process reaches browsers served by another.

Two web processes behind one database and one Redis; and on the embedded
SQLite default, a writer in its own process (as the collector is) and a web
process, with no Redis and no PostgreSQL NOTIFY to carry the wake-up.
"""

import asyncio
import json
import os

import pytest
import requests
import websockets

from tests.support.browser import session_code
from tests.support.web import WebServer

# On SpatiaLite too: several processes share one SQLite file or one PostgreSQL.
pytestmark = pytest.mark.spatialite

SESSION = (
    session_code("watcher", "operator")
    + """
from events.models import Vehicle
from events.services import logs
from rest_framework.authtoken.models import Token
leg = logs.create_leg(shift=logs.create_shift(
    test_event=logs.create_test_event(),
    vehicle=Vehicle.objects.create(key="two", short_description="two")))
print("SESSION", s.session_key, Token.objects.create(user=user).key, leg.pk)
"""
)


@pytest.fixture
def two_servers(tmp_path):
    redis_url = os.environ.get("FTT_TEST_REDIS_URL")
    if not redis_url:
        pytest.skip("needs FTT_TEST_REDIS_URL")
    # Polling once an hour: a change can only arrive through Redis's wake-up.
    env = {"FTT_DATA_DIR": str(tmp_path), "FTT_REDIS_URL": redis_url, "FTT_LIVE_POLL_MS": "3600000"}
    servers = []
    try:
        for name in ("a", "b"):
            server = WebServer(env, log=tmp_path / f"server-{name}.log")
            servers.append(server.start(migrate=not servers))
        yield servers
    finally:
        for server in servers:
            server.stop()


async def first_change(url: str, cookie: str, leg: int, ready: asyncio.Event, timeout=20):
    async with websockets.connect(
        url, additional_headers={"Cookie": cookie, "Origin": "http://127.0.0.1"}
    ) as ws:
        await ws.send(json.dumps({"type": "subscribe", "leg": leg}))
        async with asyncio.timeout(timeout):
            while json.loads(await ws.recv())["type"] != "subscribed":
                pass
            ready.set()
            while True:
                message = json.loads(await ws.recv())
                if message["type"] == "events":
                    return [event["kind"] for event in message["events"]]


def signed_in(server) -> tuple[str, str, str]:
    out = server.python(SESSION)
    _, session, token, leg = next(
        line for line in out.splitlines() if line.startswith("SESSION")
    ).split()
    return session, token, leg


def test_a_mode_report_on_one_process_reaches_browsers_on_both(two_servers):
    a, b = two_servers
    session, token, leg = signed_in(a)

    async def drill():
        ready = [asyncio.Event(), asyncio.Event()]
        watchers = [
            asyncio.create_task(
                first_change(
                    f"ws://127.0.0.1:{s.port}/ws/live/", f"sessionid={session}", int(leg), r
                )
            )
            for s, r in zip(two_servers, ready, strict=True)
        ]
        await asyncio.gather(*(r.wait() for r in ready))
        answer = await asyncio.to_thread(
            requests.post,
            f"{a.url}/api/legs/{leg}/mode/",
            json={"mode": "auto"},
            headers={"Authorization": f"Token {token}"},
            timeout=30,
        )
        assert answer.status_code == 201, answer.text
        return await asyncio.gather(*watchers)

    seen_on_a, seen_on_b = asyncio.run(drill())
    assert "segment" in seen_on_a
    assert "segment" in seen_on_b


@pytest.fixture
def sqlite_server(tmp_path):
    # No FTT_DATABASE_URL and no Redis: the embedded default. Polling once an
    # hour: a change can only arrive through the wake-up socket. A data folder
    # deeper than a socket's path may be long (107 bytes), as an institution's
    # shared drives are.
    data = tmp_path / "projects" / "field-tests-of-our-autonomous-vehicles" / "ftt-data"
    data.mkdir(parents=True)
    server = WebServer(
        {"FTT_DATA_DIR": str(data), "FTT_LIVE_POLL_MS": "3600000"},
        log=tmp_path / "server.log",
    )
    try:
        yield server.start()
    finally:
        server.stop()


def test_on_sqlite_a_write_in_another_process_reaches_the_browser_at_once(sqlite_server):
    session, _, leg = signed_in(sqlite_server)

    async def drill():
        ready = asyncio.Event()
        watcher = asyncio.create_task(
            first_change(
                f"ws://127.0.0.1:{sqlite_server.port}/ws/live/",
                f"sessionid={session}",
                int(leg),
                ready,
            )
        )
        await ready.wait()
        # A process of its own, like ftt_collect beside the web server.
        await asyncio.to_thread(
            sqlite_server.python,
            f"""
from events.models import Leg
from events.services import segments
segments.report_mode(Leg.objects.get(pk={leg}), "auto")
""",
        )
        return await watcher

    assert "segment" in asyncio.run(drill())
