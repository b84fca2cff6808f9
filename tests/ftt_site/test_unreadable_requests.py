"""A request the production server's HTTP parser cannot read (an address of
about 64 KB and more, as a search area of thousands of vertices makes) is
answered in the API's JSON error shape, pointing to a POST body."""

import http.client
import json
import threading

import pytest
import uvicorn

from ftt_site.server.web_worker import HeaderTimeoutProtocol
from tests.support.web import free_port


async def _reads(scope, receive, send):
    await send({"type": "http.response.start", "status": 200, "headers": []})
    await send({"type": "http.response.body", "body": b"read"})


@pytest.fixture
def port():
    chosen = free_port()
    config = uvicorn.Config(
        _reads, port=chosen, http=HeaderTimeoutProtocol, lifespan="off", log_level="error"
    )
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        while not server.started and thread.is_alive():
            thread.join(0.05)
        yield chosen
    finally:
        server.should_exit = True
        thread.join(10)


def get(port: int, path: str):
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.request("GET", path)
    answer = connection.getresponse()
    return answer.status, answer.getheader("Content-Type"), answer.read()


def test_an_address_too_long_to_read_is_answered_as_json(port):
    assert get(port, "/api/segments/found/?within=short")[0] == 200
    status, kind, body = get(port, "/api/segments/found/?within=" + "7" * 70000)
    assert (status, kind) == (400, "application/json")
    answer = json.loads(body)
    assert "POST" in answer["detail"] and answer["errors"] == {}
