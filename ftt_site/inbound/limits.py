"""Limits every HTTP request meets before Django reads it.

Size. Django's ASGI handler reads a whole request body (spooled to disk above
``FILE_UPLOAD_MAX_MEMORY_SIZE``) before routing or authentication, so a size
limit in a view comes too late. Here a body is refused with 413 as soon as its
``Content-Length`` (or, for a chunked body, the bytes so far) is over its limit:
``FTT_MAX_REQUEST_BODY``, or ``FTT_MAX_UPLOAD_SIZE`` on an upload address for
an account that may upload there (ftt_site.inbound.uploaders). Who comes before how
much: a larger body from anyone else is answered 401/403 before it is read.

Time. A body must keep arriving: after ``FTT_BODY_GRACE_SECONDS`` at no less
than ``FTT_BODY_MIN_RATE`` bytes per second on average, or it is answered 408
and the connection closed. (Headers have their own limit, ftt_site.server.web_worker.)

Slots. Under ASGI each request runs in a thread of its own; hundreds of
concurrent requests mean hundreds of threads fighting for the GIL and the
database lock. At most ``active`` requests run in the application at once per
process; the rest wait (cheaply, in the event loop) up to ``queue_timeout``
seconds and are then refused with 503 and ``Retry-After``. A request takes its
slot only when its whole body has arrived, so a slow client waits for bytes
without holding one, and leaves it when its response starts, so a long download
does not hold one either.
"""

import asyncio
import json
import time

from channels.db import database_sync_to_async
from django.conf import settings

from common.api.errors import BUSY_DETAIL, RETRY_AFTER_SECONDS
from ftt_site.inbound import uploaders

TOO_LARGE = "The request body is larger than this address accepts."
TOO_SLOW = "The request body arrived too slowly."


def _content_length(scope) -> int | None:
    value = uploaders.header(scope, b"content-length")
    try:
        return None if value is None else int(value)
    except ValueError:
        return None


async def _refuse(send, status: int, detail: str, headers=()):
    body = json.dumps({"detail": detail, "errors": {}}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                (b"connection", b"close"),
                *headers,
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


class RequestLimits:
    def __init__(self, app):
        self.app = app
        self.max_body = settings.FTT_MAX_REQUEST_BODY
        self.max_upload = settings.FTT_MAX_UPLOAD_SIZE
        self.active = settings.FTT_MAX_ACTIVE_REQUESTS
        self.queue_timeout = settings.FTT_REQUEST_QUEUE_TIMEOUT
        self.grace = settings.FTT_BODY_GRACE_SECONDS
        self.min_rate = settings.FTT_BODY_MIN_RATE
        # One per event loop: an asyncio.Semaphore belongs to the loop it is used in.
        self._slots: dict[asyncio.AbstractEventLoop, asyncio.Semaphore] = {}

    async def body_limit(self, scope, length: int | None) -> int | tuple[int, str]:
        """The largest body this request may send, or the (status, detail) refusing it."""
        may_be_large = length is None or length > self.max_body
        has_body = length is not None or uploaders.header(scope, b"transfer-encoding") is not None
        if not (has_body and may_be_large and uploaders.is_upload_path(scope["path"])):
            return self.max_body
        refusal = await database_sync_to_async(uploaders.refusal)(scope)
        if refusal is None:
            return self.max_upload
        # A chunked body of unknown size may still be a small one.
        return self.max_body if length is None else refusal

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        length = _content_length(scope)
        limit = await self.body_limit(scope, length)
        if isinstance(limit, tuple):
            return await _refuse(send, *limit)
        if length is not None and length > limit:
            return await _refuse(send, 413, TOO_LARGE)
        slots = self._slots.setdefault(asyncio.get_running_loop(), asyncio.Semaphore(self.active))
        state = {"held": False, "started": False, "received": 0, "complete": False}
        begun = time.monotonic()

        def release():
            if state["held"]:
                state["held"] = False
                slots.release()

        async def refuse(status, detail, headers=()):
            """Answer (unless the application already did) and end the body."""
            if not state["started"]:
                state["started"] = True
                await _refuse(send, status, detail, headers)
            return {"type": "http.disconnect"}

        async def timed_receive():
            if state["complete"]:
                # Only the disconnect is left to wait for.
                return await receive()
            allowed = begun + self.grace + state["received"] / self.min_rate - time.monotonic()
            try:
                message = await asyncio.wait_for(receive(), max(allowed, 0))
            except TimeoutError:
                return await refuse(408, TOO_SLOW)
            if message["type"] != "http.request":
                return message
            state["received"] += len(message.get("body", b""))
            if state["received"] > limit:
                # A chunked body without Content-Length: stop reading it.
                return await refuse(413, TOO_LARGE)
            if not message.get("more_body", False):
                state["complete"] = True
                try:
                    await asyncio.wait_for(slots.acquire(), self.queue_timeout)
                except TimeoutError:
                    retry = [(b"retry-after", str(RETRY_AFTER_SECONDS).encode())]
                    return await refuse(503, BUSY_DETAIL, retry)
                state["held"] = True
            return message

        async def tracked_send(message):
            if message["type"] == "http.response.start":
                state["started"] = True
                release()
            await send(message)

        try:
            return await self.app(scope, timed_receive, tracked_send)
        finally:
            release()
