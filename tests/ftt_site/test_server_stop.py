"""Stopping the production server: Ctrl-C stops an idle server at once and lets a
request in flight finish."""

import json
import os
import re
import signal
import socket
import threading
import time
import uuid
from pathlib import Path

import pytest
import requests

from tests.support.drill import prepare
from tests.support.sites import copy_migrated_database
from tests.support.web import WebServer

# On SpatiaLite too: the README's server runs on the embedded database.
pytestmark = [
    pytest.mark.spatialite,
    pytest.mark.skipif(
        bool(os.environ.get("FTT_DATABASE_URL")),
        reason="drives servers of its own on the embedded database",
    ),
]


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    """One migrated SpatiaLite file that each test's server starts on."""
    folder = tmp_path_factory.mktemp("server")
    copy_migrated_database(folder)
    return folder


@pytest.fixture
def server(data_dir):
    env = {"FTT_DATA_DIR": str(data_dir)}
    web = WebServer(env, log=data_dir / f"server-{uuid.uuid4().hex[:6]}.log").start(migrate=False)
    yield web
    web.stop()


def refuses_connections(server) -> bool:
    try:
        with socket.create_connection(("127.0.0.1", server.port), timeout=1):
            return False
    except OSError:
        return True


def wait_until_refused(server, timeout: float = 10) -> None:
    deadline = time.monotonic() + timeout
    while not refuses_connections(server):
        assert time.monotonic() < deadline, "still accepting connections after SIGINT"
        time.sleep(0.05)


@pytest.mark.parametrize("group", [False, True], ids=["kill-INT-master", "ctrl-c-group"])
def test_an_idle_server_stops_within_two_seconds_of_sigint(server, group):
    # What a browser leaves behind: a keep-alive connection after its last request.
    browser = requests.Session()
    assert browser.get(f"{server.url}/login/", timeout=10).status_code == 200
    started = time.monotonic()
    server.interrupt(group=group)
    server.process.wait(30)
    took = time.monotonic() - started
    assert took < 2.0, (took, server.log_path.read_text()[-2000:])
    assert refuses_connections(server)


def test_sigint_lets_a_request_in_flight_finish(server):
    setup = prepare(server)
    uid = str(uuid.uuid4())
    body = json.dumps({"uid": uid, "segment": setup["segment"], "text": "sent slowly"}).encode()
    head = (
        "POST /api/notes/ HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        f"Authorization: Token {setup['token']}\r\nContent-Type: application/json\r\n"
        f"Content-Length: {len(body)}\r\nExpect: 100-continue\r\n\r\n"
    ).encode()
    with socket.create_connection(("127.0.0.1", server.port), timeout=30) as robot:
        robot.sendall(head)
        # "100 Continue" comes when the application asks for the body: in flight.
        assert robot.recv(1024).startswith(b"HTTP/1.1 100 Continue\r\n\r\n")
        server.interrupt()
        wait_until_refused(server)
        robot.sendall(body)
        answer = b""
        while chunk := robot.recv(65536):
            answer += chunk
    assert answer.startswith(b"HTTP/1.1 201 "), answer[:500]
    assert server.process.wait(30) == 0
    count = server.python(
        f"from events.models import Note; print(Note.objects.filter(uid={uid!r}).count())"
    )
    assert count.split()[-1] == "1"


def running(pid: str) -> bool:
    try:
        return "State:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False


def test_a_hup_replaces_the_workers_and_refuses_no_request(server):
    """README, Production: ``kill -HUP <master>`` swaps the workers gracefully
    (with the code the master preloaded); a robot sending meanwhile is answered."""
    log = server.log_path.read_text
    old = re.findall(r"Booting worker with pid: (\d+)", log())[-1]
    answers, stop = [], threading.Event()

    def robot():
        with requests.Session() as session:
            while not stop.is_set():
                try:
                    answers.append(session.get(f"{server.url}/login/", timeout=30).status_code)
                except requests.RequestException as error:
                    answers.append(repr(error))

    sender = threading.Thread(target=robot)
    sender.start()
    try:
        deadline = time.monotonic() + 5
        while not answers and time.monotonic() < deadline:
            time.sleep(0.05)
        server.process.send_signal(signal.SIGHUP)
        deadline = time.monotonic() + 90
        while re.findall(r"Booting worker with pid: (\d+)", log())[-1] == old or running(old):
            assert time.monotonic() < deadline, log()[-3000:]
            time.sleep(0.1)
        # A moment of traffic on the new worker alone.
        seen = len(answers)
        while len(answers) < seen + 20:
            assert time.monotonic() < deadline, log()[-3000:]
            time.sleep(0.05)
    finally:
        stop.set()
        sender.join(30)
    assert set(answers) == {200}, [a for a in answers if a != 200][:5]
    assert server.process.poll() is None
