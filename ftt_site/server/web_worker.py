"""The Gunicorn worker of FTT's production server (ftt_site/server/gunicorn.conf.py):
Uvicorn's, with two differences.

* The supervisor's quick-stop signal stops it. Gunicorn's master answers SIGINT
  (Ctrl-C) and SIGQUIT by sending its workers SIGQUIT, which Uvicorn's worker
  only notes without stopping its server, so the master waited its whole
  graceful timeout. Here SIGQUIT becomes the SIGTERM that Uvicorn stops on: the
  listening socket, idle keep-alive connections and websockets (code 1012,
  "service restart": the live pages reconnect) close at once, requests in
  flight finish within the master's graceful timeout.
* A time limit on request headers. Uvicorn times out an idle keep-alive
  connection but not one that opened, or began a request, and then sends its
  headers slowly or not at all. Here a request's headers must be complete
  ``FTT_HEADER_TIMEOUT`` seconds after the connection opened or the request
  began, or the connection is closed. Slow bodies are ftt_site.inbound.limits'
  concern: they are visible to the application.
* A request the HTTP parser cannot read (a request line or headers over its
  limit of about 64 KB, e.g. a search area of thousands of vertices in the
  URL) is answered in the API's JSON error shape instead of Uvicorn's plain
  text, saying that large values go in a POST body.

Forwarded headers are left to the application (``ftt_site.inbound.proxies``).
"""

import json
import os
import signal

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol
from uvicorn_worker import UvicornWorker

# Read here rather than from Django's settings: the worker class is loaded by
# Gunicorn before (and whether or not) Django is.
HEADER_TIMEOUT = float(os.environ.get("FTT_HEADER_TIMEOUT") or 10)


UNREADABLE = (
    "The request could not be read: its address or headers are too long or malformed. "
    "Send large values, such as a search area, in the body of a POST."
)


class HeaderTimeoutProtocol(HttpToolsProtocol):
    header_timer = None

    def arm_header_timer(self) -> None:
        self.disarm_header_timer()
        self.header_timer = self.loop.call_later(HEADER_TIMEOUT, self.headers_too_slow)

    def disarm_header_timer(self) -> None:
        if self.header_timer is not None:
            self.header_timer.cancel()
            self.header_timer = None

    def headers_too_slow(self) -> None:
        self.header_timer = None
        if not self.transport.is_closing():
            self.transport.close()

    def connection_made(self, transport) -> None:
        super().connection_made(transport)
        self.arm_header_timer()

    def connection_lost(self, exc) -> None:
        self.disarm_header_timer()
        super().connection_lost(exc)

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self.arm_header_timer()

    def on_headers_complete(self) -> None:
        self.disarm_header_timer()
        super().on_headers_complete()

    def handle_websocket_upgrade(self) -> None:
        self.disarm_header_timer()
        super().handle_websocket_upgrade()

    def send_400_response(self, msg: str) -> None:
        # Django is not loaded here (nor its translations): English, as Uvicorn's.
        body = json.dumps({"detail": UNREADABLE, "errors": {}}).encode()
        head = [b"HTTP/1.1 400 Bad Request\r\n"]
        head += [
            name + b": " + value + b"\r\n" for name, value in self.server_state.default_headers
        ]
        head += [
            b"content-type: application/json\r\n",
            b"content-length: " + str(len(body)).encode() + b"\r\n",
            b"connection: close\r\n\r\n",
        ]
        self.transport.write(b"".join(head) + body)
        self.transport.close()


class Worker(UvicornWorker):
    # No proxy headers here: Uvicorn would believe X-Forwarded-For from loopback
    # whatever FTT_BEHIND_PROXY says; ftt_site.inbound.proxies is their one reader.
    CONFIG_KWARGS = {"loop": "auto", "http": HeaderTimeoutProtocol, "proxy_headers": False}

    def handle_exit(self, sig, frame):
        super().handle_exit(sig, frame)
        if sig == signal.SIGQUIT:
            signal.raise_signal(signal.SIGTERM)
