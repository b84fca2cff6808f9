"""Clients that send slowly, or stop, cannot keep a robot's poses out (issue 31,
finding 1), against the production server (Gunicorn + Uvicorn as scripts/run.sh
starts it)."""

import json
import os
import socket
import time
import uuid
from contextlib import ExitStack

import pytest
import requests

from tests.support.web import WebServer

ROBOT = """
import json
from events.models import Vehicle
from events.services import logs, segments
from events.services.robots import ensure_robot_account

# On SpatiaLite only: drives a server of its own on the embedded database.
pytestmark = pytest.mark.spatialite
vehicle, _ = Vehicle.objects.get_or_create(key="slow", defaults={"short_description": "slow"})
login = ensure_robot_account("slow-robot", [vehicle], new_token=True)
leg = logs.create_leg(shift=logs.create_shift(
    test_event=logs.create_test_event(location="slow"), vehicle=vehicle))
print(json.dumps({"token": login.token, "segment": segments.report_mode(leg, "auto").master.pk}))
"""

GRACE = 3
HEADER_TIMEOUT = 3


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    data_dir = tmp_path_factory.mktemp("slow")
    env = {
        "FTT_DATA_DIR": str(data_dir),
        "FTT_BODY_GRACE_SECONDS": str(GRACE),
        "FTT_HEADER_TIMEOUT": str(HEADER_TIMEOUT),
    }
    web = WebServer(env, workers=1, log=data_dir / "server.log").start()
    yield web
    web.stop()


@pytest.fixture(scope="module")
def robot(server):
    return json.loads(server.python(ROBOT).strip().splitlines()[-1])


def post_pose(server, robot) -> requests.Response:
    body = {"segment": robot["segment"], "longitude": 7.1, "latitude": 50.2}
    return requests.post(
        f"{server.url}/api/poses/",
        json={**body, "uid": str(uuid.uuid4())},
        headers={"Authorization": f"Token {robot['token']}"},
        timeout=30,
    )


def open_login_post(server, length=100) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", server.port), timeout=30)
    sock.sendall(
        (
            "POST /login/ HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            "Content-Type: application/x-www-form-urlencoded\r\n"
            f"Content-Length: {length}\r\n\r\n"
        ).encode()
    )
    return sock


def answer_of(sock) -> tuple[str, float]:
    """The status line the server sends (empty: it only closed), and when."""
    data = b""
    while chunk := sock.recv(4096):
        data += chunk
    return data.decode(errors="replace").split("\r\n", 1)[0], time.monotonic()


def test_silent_and_trickling_bodies_do_not_stop_a_robots_pose(server, robot):
    assert post_pose(server, robot).status_code == 201
    with ExitStack() as stack:
        # More of each than the server runs requests at once (FTT_MAX_ACTIVE_REQUESTS, 8).
        silent = [stack.enter_context(open_login_post(server)) for _ in range(12)]
        trickling = [stack.enter_context(open_login_post(server)) for _ in range(12)]
        for _ in range(3):
            for sock in trickling:
                sock.sendall(b"a")
            started = time.monotonic()
            response = post_pose(server, robot)
            assert response.status_code == 201, response.text
            assert time.monotonic() - started < 2
            time.sleep(0.5)
        assert len(silent) == 12


def test_a_body_that_stops_is_answered_408_and_closed(server):
    started = time.monotonic()
    with open_login_post(server) as sock:
        sock.sendall(b"username=x")
        status, ended = answer_of(sock)
    assert status.startswith("HTTP/1.1 408"), status
    assert ended - started < GRACE + 2


def test_a_body_trickling_below_the_floor_rate_is_dropped(server):
    started = time.monotonic()
    received, answered, closed = b"", None, False
    with open_login_post(server, length=100_000) as sock:
        sock.settimeout(0.5)
        # Each read keeps what came before it: a 408 split over two reads, or
        # followed by a slow close, is still the answer.
        while not closed and time.monotonic() - started < GRACE + 10:
            try:
                if not received:
                    sock.sendall(b"a")  # two bytes a second, far below the floor rate
                chunk = sock.recv(4096)
            except TimeoutError:
                continue
            except (BrokenPipeError, ConnectionResetError):
                closed = True
                break
            closed = not chunk
            if chunk and answered is None:
                answered = time.monotonic() - started
            received += chunk
    status = received.decode(errors="replace").split("\r\n", 1)[0]
    shown = f"{received[:200]!r}; answered after {answered} s; closed: {closed}"
    assert status.startswith("HTTP/1.1 408"), shown
    assert answered < GRACE + 3, shown
    assert closed, shown


def test_headers_that_never_end_close_the_connection(server):
    started = time.monotonic()
    with socket.create_connection(("127.0.0.1", server.port), timeout=30) as sock:
        sock.sendall(b"POST /login/ HTTP/1.1\r\nHost: 127.0.0.1\r\n")
        status, ended = answer_of(sock)
    assert status == ""
    assert ended - started < HEADER_TIMEOUT + 2
