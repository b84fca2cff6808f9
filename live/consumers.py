"""Websocket side of the live change feed (see events.feed).

One feed reader per event loop reads new feed rows every FTT_LIVE_POLL_MS,
however many browsers are connected, and hands them to the consumers, which
filter them by what each browser watches.  A commit wakes it at once
(live.wakeup): on PostgreSQL it LISTENs on its own connection, on
SQLite a datagram arrives on its socket, with Redis the group message arrives,
and writes of this process call it directly.
A browser that reconnects says which event it saw last and gets what it missed
from the feed, which stays the source of truth.
"""

import asyncio
import logging
import time
from collections import Counter
from importlib import import_module
from types import SimpleNamespace

from channels.db import database_sync_to_async
from channels.exceptions import StopConsumer
from channels.generic.websocket import AsyncJsonWebsocketConsumer
from django.conf import settings
from django.contrib import auth
from django.core.serializers.json import DjangoJSONEncoder
from django.db import connections
from django.utils import translation
from django.utils.translation import gettext
from psycopg import AsyncConnection

from common import roles
from common.metrics import LIVE_CONNECTIONS
from common.sql import conninfo
from events import feed
from events.api.serializers import touched_rows
from events.feed import FLEET_KINDS, LOG_KINDS
from events.models import Announcement
from live import wakeup
from live.sessions import session_group
from live.wakeup import CHANNEL, GROUP
from rosbridge_app.selectors.fleet import fleet as fleet_entries

logger = logging.getLogger(__name__)

POLL_INTERVAL = settings.FTT_LIVE_POLL_MS / 1000
# After a lost database connection the listener tries again this much later.
LISTEN_RETRY = 2.0
BATCH = 1000
# Ids are taken when a transaction inserts and become visible when it commits;
# on PostgreSQL a smaller id can therefore appear after a larger one.  A gap
# is waited for this long before it is taken as a rolled-back insert.
GAP_PATIENCE = 5.0
CATCH_UP_LIMIT = 5000
# How often an open websocket asks whether its session and role still hold.
SESSION_CHECK_INTERVAL = 30.0
# A page that has heard nothing for this many heartbeats shows its link stale.
MISSED_BEATS = 3


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
def _rows_after(after: int, limit: int = BATCH, *, fleet: bool = False) -> list[dict]:
    """Feed rows after ``after``; ``fleet``: a fleet view watches, so each of its
    kinds carries its vehicle's entry."""
    rows = [as_message(e) for e in feed.after(after, limit)]
    _attach_segments([r for r in rows if r["kind"] == Announcement.Kind.SEGMENT])
    if fleet:
        _attach_fleet([r for r in rows if r["kind"] in FLEET_KINDS and r["leg"] is not None])
    return rows


def _attach_fleet(rows: list[dict]) -> None:
    """Give each mode and position row the fleet entry of the vehicle logging into
    its leg, as the fleet view's first read gives it (rosbridge_app.selectors.fleet),
    read after the rows: the page shows it and computes nothing.  None when no
    vehicle logs into the leg now, and the page reads the fleet again.  One query
    however many rows."""
    if not rows:
        return
    entries = {entry["leg"]["id"]: entry for entry in fleet_entries(legs={r["leg"] for r in rows})}
    for row in rows:
        row["fleet"] = entries.get(row["leg"])


def _attach_segments(rows: list[dict]) -> None:
    """Give each segment event the rows it changed, as the API shows them, with
    their labels, so the page applies them instead of re-reading the list.
    Four queries however many events the batch holds; a segment deleted since
    gets none, and the page re-reads."""
    touched = touched_rows({r["payload"].get("id") for r in rows} - {None})
    for row in rows:
        row.update(touched.get(row["payload"].get("id"), {}))


_bounds = database_sync_to_async(feed.bounds)


def _log_timing(step: str, rows: list[dict], **times: float) -> None:
    """At DEBUG: when segment rows were read or sent (epoch seconds), to see
    which stage of a mode switch's way to the screen is slow on an installation
    (`FTT_LOG_LEVEL=DEBUG`; benchmarks/live_latency.py reads the same lines)."""
    ids = [r["id"] for r in rows if r["kind"] == Announcement.Kind.SEGMENT]
    if ids:
        extra = "".join(f" {key}={value:.6f}" for key, value in times.items())
        logger.debug("live %s segments=%s at=%.6f%s", step, ids, time.time(), extra)


class FeedReader:
    """Reads the feed once for all consumers of one event loop."""

    _by_loop: dict = {}

    def __init__(self):
        self.consumers: set = set()
        self.floor: int | None = None  # every id <= floor was handled
        self.seen: set[int] = set()  # handled ids above floor
        self.gap_since: float | None = None
        self.wakeup = asyncio.Event()
        self.task: asyncio.Task | None = None
        self.listener: asyncio.Task | None = None
        self.sqlite_listener: wakeup.SqliteListener | None = None
        self.wake_from_thread = None
        self.notified = 0.0  # when the last NOTIFY arrived (time.time(), for the debug log)

    @classmethod
    def for_loop(cls) -> "FeedReader":
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
            loop = asyncio.get_running_loop()
            self.task = loop.create_task(self._run())
            self.wake_from_thread = lambda: loop.call_soon_threadsafe(self.wakeup.set)
            wakeup.local_readers.add(self.wake_from_thread)
            if connections["default"].vendor == "postgresql":
                self.listener = loop.create_task(self._listen())
            self._listen_sqlite(loop)

    def remove(self, consumer) -> None:
        self.consumers.discard(consumer)
        if not self.consumers and self.task is not None:
            self.task.cancel()
            self.task = None
            if self.listener is not None:
                self.listener.cancel()
                self.listener = None
            wakeup.local_readers.discard(self.wake_from_thread)
            if self.sqlite_listener is not None:
                self.sqlite_loop.remove_reader(self.sqlite_listener)
                self.sqlite_listener.close()
                self.sqlite_listener = None
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
                logger.exception("live feed read failed")
            try:
                await asyncio.wait_for(self.wakeup.wait(), POLL_INTERVAL)
            except TimeoutError:
                pass
            self.wakeup.clear()

    async def _listen(self) -> None:
        """Wake the poller on every NOTIFY of the feed (a commit in any process)."""
        while True:
            try:
                async with await AsyncConnection.connect(conninfo(), autocommit=True) as conn:
                    await conn.execute(f"LISTEN {CHANNEL}")
                    # Rows committed while (re)connecting are found by this read.
                    self.wakeup.set()
                    async for _ in conn.notifies():
                        self.notified = time.time()
                        self.wakeup.set()
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # noqa: BLE001 - polling goes on meanwhile
                logger.warning("live listener lost its connection: %s", exc)
            await asyncio.sleep(LISTEN_RETRY)

    def _listen_sqlite(self, loop) -> None:
        folder = wakeup.socket_folder()
        if folder is None:
            return
        try:
            listener = wakeup.SqliteListener(folder)
        except OSError as exc:  # polling goes on without it
            logger.warning("live wake-up socket not opened: %s", exc)
            return

        def woken():
            listener.drain()
            self.wakeup.set()

        loop.add_reader(listener, woken)
        self.sqlite_listener, self.sqlite_loop = listener, loop

    async def poll_once(self) -> list[dict]:
        asked = time.time()
        watched = any(consumer.fleet for consumer in self.consumers)
        rows = [r for r in await _rows_after(self.floor, fleet=watched) if r["id"] not in self.seen]
        if logger.isEnabledFor(logging.DEBUG):
            _log_timing("read", rows, notified=self.notified, asked=asked)
        for row in rows:
            self.seen.add(row["id"])
        self._advance_floor()
        if rows:
            for consumer in list(self.consumers):
                await self._deliver(consumer, rows)
        return rows

    async def _deliver(self, consumer, rows: list[dict]) -> None:
        """One consumer's failure neither stops the others nor repeats every poll."""
        try:
            await consumer.deliver(rows)
        except StopConsumer:
            pass  # its socket closed; the consumer has left already
        except Exception:  # noqa: BLE001 - the rows are marked seen: the others must get them
            logger.exception("live delivery failed; the socket is dropped")
            self.remove(consumer)

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


@database_sync_to_async
def _still_allowed(scope) -> bool:
    """Read afresh whether the socket's user may still watch: a logout deletes the
    session, an administrator may take the role away or deactivate the account."""
    session = scope.get("session")
    key = getattr(session, "session_key", None)
    if key:
        engine = import_module(settings.SESSION_ENGINE)
        user = auth.get_user(SimpleNamespace(session=engine.SessionStore(key)))
    else:
        known = scope.get("user")
        pk = getattr(known, "pk", None)
        user = auth.get_user_model().objects.filter(pk=pk).first() if pk else None
    return roles.has_role(user, roles.VIEWER)


# Live links open per account and per client address in this process: one
# viewer opening hundreds would make every poll and wake-up slow for everybody.
_OPEN_LINKS: Counter = Counter()


def _holders(scope) -> tuple:
    account = ("account", getattr(scope.get("user"), "pk", None))
    client = scope.get("client")
    return (account, ("address", client[0])) if client else (account,)


def _take_link(holders: tuple) -> bool:
    limits = {
        "account": settings.FTT_LIVE_LINKS_PER_ACCOUNT,
        "address": settings.FTT_LIVE_LINKS_PER_ADDRESS,
    }
    if any(_OPEN_LINKS[h] >= limits[h[0]] for h in holders):
        return False
    _OPEN_LINKS.update(holders)
    return True


def _give_back(holders: tuple) -> None:
    _OPEN_LINKS.subtract(holders)
    for holder in holders:
        if _OPEN_LINKS[holder] <= 0:
            del _OPEN_LINKS[holder]


class LiveConsumer(AsyncJsonWebsocketConsumer):
    """ws/live/: the browser subscribes with the ids it shows and its last seen event id."""

    async def connect(self):
        if not await _still_allowed(self.scope):
            await self.close(code=4403)
            return
        self.holds = _holders(self.scope)
        if not _take_link(self.holds):
            self.holds = ()
            await self.close(code=4429)  # too many live links of this account or address
            return
        self.watch = {"test_event": None, "shift": None, "leg": None}
        self.fleet = False
        self.language = settings.LANGUAGE_CODE
        self.subscribed = False
        self.sent: set[int] = set()
        self.poller = FeedReader.for_loop()
        await self.accept()
        LIVE_CONNECTIONS.inc()
        await self.poller.add(self)
        if getattr(settings, "REDIS_URL", "") and self.channel_layer is not None:
            await self.channel_layer.group_add(GROUP, self.channel_name)
        key = getattr(self.scope.get("session"), "session_key", None)
        self.session_group = session_group(key) if key and self.channel_layer else None
        if self.session_group:
            await self.channel_layer.group_add(self.session_group, self.channel_name)
        loop = asyncio.get_running_loop()
        self.guard = loop.create_task(self._guard_session())
        self.heart = loop.create_task(self._beat())

    async def _beat(self) -> None:
        """Speak every FTT_LIVE_HEARTBEAT_MS, events or not: a half-open Wi-Fi link
        stays "open" to the browser, and only silence tells it the link is dead."""
        while True:
            every = settings.FTT_LIVE_HEARTBEAT_MS
            await asyncio.sleep(every / 1000)
            try:
                await self.send_json(
                    {"type": "heartbeat", "stale_after": every * MISSED_BEATS / 1000}
                )
            except StopConsumer:
                return

    async def _guard_session(self) -> None:
        while True:
            await asyncio.sleep(SESSION_CHECK_INTERVAL)
            try:
                if not await self._session_holds():
                    return
            except StopConsumer:
                return

    async def _session_holds(self) -> bool:
        if await _still_allowed(self.scope):
            return True
        await self._end_session()
        return False

    async def _end_session(self) -> None:
        await self.send_json(
            {"type": "error", "detail": gettext("Your session has ended; sign in again.")}
        )
        await self.close(code=4401)

    async def session_ended(self, message):
        """A logout in this socket's session (live.sessions)."""
        await self._end_session()

    async def encode_json(self, content):
        """Events are read once for every page; their words (segment labels, lazy)
        are written in this page's language."""
        with translation.override(self.language):
            return DjangoJSONEncoder().encode(content)

    async def send_json(self, content, close=False):
        """Send, or leave at once if the browser has gone: Uvicorn raises
        ClientDisconnected (an OSError) and then never calls disconnect()."""
        try:
            await super().send_json(content, close)
        except OSError as exc:
            logger.info("live socket closed while sending: %r", exc)
            await self.disconnect(None)
            raise StopConsumer from exc

    async def disconnect(self, code):
        """Leave the poller and the groups; safe to call twice."""
        if getattr(self, "gone", False):
            return
        self.gone = True
        _give_back(getattr(self, "holds", ()))
        for task in (getattr(self, "guard", None), getattr(self, "heart", None)):
            if task is not None and task is not asyncio.current_task():
                task.cancel()
        group = getattr(self, "session_group", None)
        if group:
            await self.channel_layer.group_discard(group, self.channel_name)
        poller = getattr(self, "poller", None)
        if poller is not None:
            LIVE_CONNECTIONS.dec()
            poller.remove(self)
            if getattr(settings, "REDIS_URL", "") and self.channel_layer is not None:
                await self.channel_layer.group_discard(GROUP, self.channel_name)

    async def receive(self, text_data=None, bytes_data=None, **kwargs):
        try:
            content = await self.decode_json(text_data) if text_data else None
        except ValueError:
            content = None
        if not isinstance(content, dict):
            await self.send_json({"type": "error", "detail": gettext("Send one JSON object.")})
            return
        await self.receive_json(content, **kwargs)

    async def receive_json(self, content, **kwargs):
        if not await self._session_holds():
            return
        if content.get("type") != "subscribe":
            await self.send_json({"type": "error", "detail": gettext("Unknown message.")})
            return
        for key in self.watch:
            value = content.get(key)
            self.watch[key] = value if isinstance(value, int) and value > 0 else None
        # The fleet view watches every logging robot, not one leg.
        self.fleet = content.get("fleet") is True
        # The page's language, which the server chose for it: the words events carry.
        language = content.get("language")
        if language in dict(settings.LANGUAGES):
            self.language = language
        last_id = content.get("last_id")
        first, last = await _bounds()
        if isinstance(last_id, int) and last_id < last:
            if last_id < first - 1:
                # What was missed has been pruned: the page must load afresh.
                await self.send_json({"type": "reset", "last_id": last})
            else:
                missed = await _rows_after(last_id, CATCH_UP_LIMIT, fleet=self.fleet)
                if len(missed) == CATCH_UP_LIMIT:
                    await self.send_json({"type": "reset", "last_id": last})
                else:
                    await self.deliver(missed)
        self.subscribed = True
        await self.send_json({"type": "subscribed", "last_id": last})

    def wants(self, event: dict) -> bool:
        if event["kind"] in LOG_KINDS or (self.fleet and event["kind"] in FLEET_KINDS):
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
        if logger.isEnabledFor(logging.DEBUG):
            _log_timing("sent", fresh)

    async def live_wake(self, message):
        self.poller.wake()
