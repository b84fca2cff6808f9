"""The production server (Gunicorn + Uvicorn, as README starts it) under abuse and load."""

import json
import os
import socket
import time

import pytest

from tests.support.drill import prepare, run_drill, stored
from tests.support.ros import wait_for
from tests.support.web import WebServer

# On SpatiaLite too: the README's server runs on the embedded database.
pytestmark = pytest.mark.spatialite

MB = 1024 * 1024


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    data_dir = tmp_path_factory.mktemp("server")
    # Where the server's temporary upload files go (tempfile reads TMPDIR).
    (data_dir / "tmp").mkdir()
    env = {"FTT_DATA_DIR": str(data_dir), "TMPDIR": str(data_dir / "tmp")}
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    web = WebServer(env, workers=1, log=data_dir / "server.log").start()
    yield web
    web.stop()


def worker_rss(server) -> int:
    """Resident memory of the Gunicorn worker processes, in bytes."""
    total = 0
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            status = open(f"/proc/{pid}/status").read()
        except OSError:
            continue
        fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
        if int(fields["PPid"]) == server.process.pid:
            total += int(fields["VmRSS"].split()[0]) * 1024
    return total


def post_raw(server, head: str, body_chunks, pause_for_answer=True) -> tuple[str, int]:
    """Send a request by hand; returns the status line and how many body bytes went out."""
    sent = 0
    with socket.create_connection(("127.0.0.1", server.port), timeout=30) as sock:
        sock.sendall(head.encode())
        try:
            for chunk in body_chunks:
                sock.sendall(chunk)
                sent += len(chunk)
        except (BrokenPipeError, ConnectionResetError):
            pass
        answer = sock.recv(4096).decode(errors="replace")
    return answer.split("\r\n", 1)[0], sent


def test_an_anonymous_300_mb_login_post_is_refused_before_its_body_is_read(server):
    before = worker_rss(server)
    started = time.monotonic()
    head = (
        "POST /login/ HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        "Content-Type: multipart/form-data; boundary=x\r\n"
        f"Content-Length: {300 * MB}\r\n\r\n"
    )
    status, sent = post_raw(server, head, [])
    assert status.startswith("HTTP/1.1 413"), status
    assert time.monotonic() - started < 5
    assert worker_rss(server) - before < 50 * MB


ACCOUNTS = """
import json
from django.contrib.auth.models import Group, User
from rest_framework.authtoken.models import Token
tokens = {}
for role in ("viewer", "operator"):
    user, _ = User.objects.get_or_create(username=f"upload-{role}")
    user.groups.add(Group.objects.get(name=role))
    tokens[role] = Token.objects.get_or_create(user=user)[0].key
print(json.dumps(tokens))
"""


@pytest.fixture(scope="module")
def tokens(server):
    return json.loads(server.python(ACCOUNTS).strip().splitlines()[-1])


def upload_head(path: str, length: int, token: str | None = None) -> str:
    authorization = f"Authorization: Token {token}\r\n" if token else ""
    return (
        f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n{authorization}"
        "Content-Type: multipart/form-data; boundary=x\r\n"
        f"Content-Length: {length}\r\n\r\n"
    )


def temporary_files(server) -> list[str]:
    return os.listdir(os.path.join(server.env["FTT_DATA_DIR"], "tmp"))


@pytest.mark.parametrize(
    "path", ["/api/images/", "/api/maps/", "/api/archives/import/", "/import/", "/admin/login/"]
)
def test_an_anonymous_100_mb_upload_is_refused_before_its_body_is_read(server, path):
    status, _ = post_raw(server, upload_head(path, 100 * MB), [])
    assert status.startswith("HTTP/1.1 401"), status
    assert temporary_files(server) == []


def test_a_viewers_100_mb_upload_is_refused_before_its_body_is_read(server, tokens):
    status, _ = post_raw(server, upload_head("/api/images/", 100 * MB, tokens["viewer"]), [])
    assert status.startswith("HTTP/1.1 403"), status


def test_an_operators_60_mb_upload_is_read_and_its_temporary_file_removed(server, tokens):
    body = b'--x\r\nContent-Disposition: form-data; name="image"; filename="a.jpg"\r\n\r\n'
    body += b"\0" * (60 * MB) + b"\r\n--x--\r\n"
    head = upload_head("/api/images/", len(body), tokens["operator"])
    status, sent = post_raw(server, head, [body[i : i + MB] for i in range(0, len(body), MB)])
    # Read in full and judged by the view: not an image.
    assert status.startswith("HTTP/1.1 400"), status
    assert sent == len(body)
    # Django removes the file when it closes the request, just after answering.
    wait_for(lambda: temporary_files(server) == [], 10, what="the temporary file removed")


def test_a_chunked_body_without_length_is_cut_off_at_the_limit(server):
    before = worker_rss(server)
    head = (
        "POST /login/ HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        "Content-Type: application/octet-stream\r\nTransfer-Encoding: chunked\r\n\r\n"
    )
    piece = b"x" * MB
    chunk = f"{len(piece):x}\r\n".encode() + piece + b"\r\n"
    status, sent = post_raw(server, head, (chunk for _ in range(300)))
    assert status.startswith("HTTP/1.1 413"), status
    # The server stops reading soon after the 50 MB limit; the socket buffers take the rest.
    assert sent < 120 * MB
    assert worker_rss(server) - before < 50 * MB


def test_concurrent_clients_are_served_or_told_to_retry_and_nothing_is_lost(server):
    setup = prepare(server)
    result = run_drill(server.url, setup, clients=20, rounds=5)
    assert 500 not in result["statuses"]
    assert result["refused"] <= 0.01 * result["requests"], result["refusal_details"]
    assert result["refused_without_retry_after"] == 0
    kept = stored(server, setup, result["created_note_uids"])
    assert kept["posted_uids_stored"] == len(result["created_note_uids"])
    assert kept["notes"] == kept["distinct_note_uids"] == len(result["created_note_uids"])
    assert kept["open_masters"] == 1
