"""Fixtures for the report tests: the hand-checkable scenario and tile servers."""

import socket
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from tests.support.images import png
from tests.support.scenario import build_open_scenario, build_scenario


@pytest.fixture
def scenario(vehicle, other_vehicle, performer, media_root):
    return build_scenario(vehicle, other_vehicle, performer)


@pytest.fixture
def open_scenario(vehicle, performer, media_root):
    return build_open_scenario(vehicle, performer)


class _TileHandler(BaseHTTPRequestHandler):
    tile = png((256, 256), (200, 230, 200))
    requests: list

    def do_GET(self):  # noqa: N802 - http.server's naming
        self.requests.append((self.path, self.headers.get("User-Agent", "")))
        self.send_response(200)
        self.send_header("Content-Type", "image/png")
        self.send_header("Content-Length", str(len(self.tile)))
        self.end_headers()
        self.wfile.write(self.tile)

    def log_message(self, *args):
        pass


@pytest.fixture
def tile_server():
    """A tile server on loopback that serves one generated PNG for every tile."""
    handler = type("Handler", (_TileHandler,), {"requests": []})
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    host, port = server.server_address
    yield type(
        "TileServer",
        (),
        {"url": f"http://{host}:{port}/{{z}}/{{x}}/{{y}}.png", "requests": handler.requests},
    )
    server.shutdown()
    server.server_close()


@pytest.fixture
def dead_tile_url():
    """A loopback URL where nothing listens."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    return f"http://127.0.0.1:{port}/{{z}}/{{x}}/{{y}}.png"
