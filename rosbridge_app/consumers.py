"""Websocket side of the live outbox (see rosbridge_app.live).

One poller per event loop reads new outbox rows every POLL_INTERVAL seconds,
however many browsers are connected, and hands them to the consumers, which
filter them by what each browser watches.  A browser that reconnects says
which event it saw last and gets what it missed from the outbox.
"""

import asyncio
import logging
import time

from channels.db import database_sync_to_async
from channels.generic.websocket import AsyncJsonWebsocketConsumer
from django.conf import settings

from events import roles
from rosbridge_app.live import GROUP, LOG_KINDS
from rosbridge_app.models import Announcement

logger = logging.getLogger(__name__)

POLL_INTERVAL = 0.2
BATCH = 1000
# Ids are taken when a transaction inserts and become visible when it commits;
# on PostgreSQL a smaller id can therefore appear after a larger one.  A gap
# is waited for this long before it is taken as a rolled-back insert.
GAP_PATIENCE = 5.0
CATCH_UP_LIMIT = 5000


def as_message(row: Announcement) -> dict:
    payload = row.payload or {}
    return {
        "id": row.pk,
        "kind": row.kind,
        "test_event": payload.get("test_event"),
        "shift": payload.get("shift"),
        "leg": row.leg_id or payload.get("leg"),
        "collector": row.collector_id,
        "payload": payload,
    }


@database_sync_to_async
def _rows_after(after: int, limit: int = BATCH) -> list[dict]:
    return [as_message(e) for e in Announcement.objects.filter(id__gt=after)[:limit]]


@database_sync_to_async
def _bounds() -> tuple[int, int]:
    first = Announcement.objects.order_by("id").values_list("id", flat=True).first()
    last = Announcement.objects.order_by("-id").values_list("id", flat=True).first()
    return first or 0, last or 0


class OutboxPoller:
    """Reads the outbox once for all consumers of one event loop."""

    _by_loop: dict = {}

    def __init__(self):
        self.consumers: set = set()
        self.floor: int | None = None  # every id <= floor was handled
        self.seen: set[int] = set()  # handled ids above floor
        self.gap_since: float | None = None
        self.wakeup = asyncio.Event()
        self.task: asyncio.Task | None = None

    @classmethod
    def for_loop(cls) -> "OutboxPoller":
        loop = asyncio.get_running_loop()
        poller = cls._by_loop.get(loop)
        if poller is None:
            poller = cls._by_loop[loop] = cls()
        return poller

    async def add(self, consumer) -> None:
        if self.floor is None:
            self.floor = (await _bounds())[1]
        self.consumers.add(consumer)
        if self.task is None or self.task.done():
            self.task = asyncio.get_running_loop().create_task(self._run())

    def remove(self, consumer) -> None:
        self.consumers.discard(consumer)
        if not self.consumers and self.task is not None:
            self.task.cancel()
            self.task = None
            self.floor = None
            self.seen.clear()

    def wake(self) -> None:
        self.wakeup.set()

    async def _run(self) -> None:
        while self.consumers:
            try:
                await self.poll_once()
            except asyncio.CancelledError:
                raise
            except Exception:  # noqa: BLE001 - a DB hiccup must not end live updates
                logger.exception("live outbox poll failed")
            try:
                await asyncio.wait_for(self.wakeup.wait(), POLL_INTERVAL)
            except TimeoutError:
                pass
            self.wakeup.clear()

    async def poll_once(self) -> list[dict]:
        rows = [r for r in await _rows_after(self.floor) if r["id"] not in self.seen]
        for row in rows:
            self.seen.add(row["id"])
        self._advance_floor()
        if rows:
            for consumer in list(self.consumers):
                await consumer.deliver(rows)
        return rows

    def _advance_floor(self) -> None:
        while self.floor + 1 in self.seen:
            self.floor += 1
            self.seen.discard(self.floor)
        if not self.seen:
            self.gap_since = None
            return
        now = time.monotonic()
        if self.gap_since is None:
            self.gap_since = now
        elif now - self.gap_since > GAP_PATIENCE:
            # The missing ids belong to rolled-back transactions: skip them.
            self.floor = min(self.seen) - 1
            self.gap_since = None
            self._advance_floor()


class LiveConsumer(AsyncJsonWebsocketConsumer):
    """ws/live/: the browser subscribes with the ids it shows and its last seen event id."""

    async def connect(self):
        user = self.scope.get("user")
        if not await database_sync_to_async(roles.has_role)(user, roles.VIEWER):
            await self.close(code=4403)
            return
        self.watch = {"test_event": None, "shift": None, "leg": None}
        self.subscribed = False
        self.sent: set[int] = set()
        self.poller = OutboxPoller.for_loop()
        await self.accept()
        await self.poller.add(self)
        if getattr(settings, "REDIS_URL", "") and self.channel_layer is not None:
            await self.channel_layer.group_add(GROUP, self.channel_name)

    async def disconnect(self, code):
        poller = getattr(self, "poller", None)
        if poller is not None:
            poller.remove(self)
            if getattr(settings, "REDIS_URL", "") and self.channel_layer is not None:
                await self.channel_layer.group_discard(GROUP, self.channel_name)

    async def receive_json(self, content, **kwargs):
        if content.get("type") != "subscribe":
            await self.send_json({"type": "error", "detail": "Unknown message."})
            return
        for key in self.watch:
            value = content.get(key)
            self.watch[key] = value if isinstance(value, int) and value > 0 else None
        last_id = content.get("last_id")
        first, last = await _bounds()
        if isinstance(last_id, int) and last_id < last:
            if last_id < first - 1:
                # What was missed has been pruned: the page must load afresh.
                await self.send_json({"type": "reset", "last_id": last})
            else:
                missed = await _rows_after(last_id, CATCH_UP_LIMIT)
                if len(missed) == CATCH_UP_LIMIT:
                    await self.send_json({"type": "reset", "last_id": last})
                else:
                    await self.deliver(missed)
        self.subscribed = True
        await self.send_json({"type": "subscribed", "last_id": last})

    def wants(self, event: dict) -> bool:
        if event["kind"] in LOG_KINDS:
            return True
        if event["leg"] is not None:
            return event["leg"] == self.watch["leg"]
        return event["shift"] is not None and event["shift"] == self.watch["shift"]

    async def deliver(self, events: list[dict]) -> None:
        fresh = [e for e in events if e["id"] not in self.sent and self.wants(e)]
        if not fresh:
            return
        self.sent.update(e["id"] for e in fresh)
        if len(self.sent) > 10000:
            self.sent = set(sorted(self.sent)[-5000:])
        await self.send_json({"type": "events", "events": fresh})

    async def live_wake(self, message):
        self.poller.wake()
