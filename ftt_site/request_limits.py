"""Limits every HTTP request meets before Django reads it.

Django's ASGI handler reads a whole request body (spooled to disk above
``FILE_UPLOAD_MAX_MEMORY_SIZE``) before routing or authentication, so a size
limit in a view comes too late: an anonymous client could fill the disk or, with
a server that buffers bodies in memory, the RAM. Here a body is refused with 413
as soon as its ``Content-Length`` (or, for a chunked body, the bytes so far) is
over the limit of its path.

Under ASGI each request runs in a thread of its own; hundreds of concurrent
requests mean hundreds of threads fighting for the GIL and the database lock.
At most ``active`` requests run in the application at once per process; the
rest wait (cheaply, in the event loop) up to ``queue_timeout`` seconds and are
then refused with 503 and ``Retry-After``. A request leaves its slot when its
response starts, so a long download does not hold one.
"""

import asyncio
import json

from django.conf import settings

from common.api.errors import BUSY_DETAIL, RETRY_AFTER_SECONDS

TOO_LARGE = "The request body is larger than this address accepts."


def _content_length(scope) -> int | None:
    for name, value in scope.get("headers", ()):
        if name == b"content-length":
            try:
                return int(value)
            except ValueError:
                return None
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
        self.upload_prefixes = tuple(settings.FTT_UPLOAD_PATHS)
        self.active = settings.FTT_MAX_ACTIVE_REQUESTS
        self.queue_timeout = settings.FTT_REQUEST_QUEUE_TIMEOUT
        # One per event loop: an asyncio.Semaphore belongs to the loop it is used in.
        self._slots: dict[asyncio.AbstractEventLoop, asyncio.Semaphore] = {}

    def body_limit(self, path: str) -> int:
        return self.max_upload if path.startswith(self.upload_prefixes) else self.max_body

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        limit = self.body_limit(scope["path"])
        length = _content_length(scope)
        if length is not None and length > limit:
            return await _refuse(send, 413, TOO_LARGE)
        slots = self._slots.setdefault(asyncio.get_running_loop(), asyncio.Semaphore(self.active))
        try:
            await asyncio.wait_for(slots.acquire(), self.queue_timeout)
        except TimeoutError:
            retry = [(b"retry-after", str(RETRY_AFTER_SECONDS).encode())]
            return await _refuse(send, 503, BUSY_DETAIL, retry)
        state = {"held": True, "started": False, "received": 0}

        def release():
            if state["held"]:
                state["held"] = False
                slots.release()

        async def bounded_receive():
            message = await receive()
            if message["type"] == "http.request":
                state["received"] += len(message.get("body", b""))
                if state["received"] > limit:
                    # A chunked body without Content-Length: stop reading it.
                    if not state["started"]:
                        await tracked_send_refusal()
                    return {"type": "http.disconnect"}
            return message

        async def tracked_send(message):
            if message["type"] == "http.response.start":
                state["started"] = True
                release()
            await send(message)

        async def tracked_send_refusal():
            state["started"] = True
            await _refuse(send, 413, TOO_LARGE)

        try:
            return await self.app(scope, bounded_receive, tracked_send)
        finally:
            release()
