"""Waking the live readers when a change-feed row commits.

Every change a browser sees goes the same way: a writer (service, collector,
importer) adds an :class:`events.models.Announcement` row in the transaction of
its change (events.feed); each web process has one reader per event loop
(live.consumers.FeedReader) that reads the rows after the last it
saw and sends them to its websockets.  The readers poll the feed every
FTT_LIVE_POLL_MS anyway; this module only makes them read at once.  It hears
each new feed row (Django's ``post_save``, so the writers, which sit in lower
layers, never call up to it) and, once the writer's transaction commits
(``transaction.on_commit``; a rolled-back change wakes nobody), wakes:

1. the readers of the writing process itself, by a direct call;
2. on SQLite, every reader of the same database file in other processes (the
   collector and the web server share nothing else): a datagram to each
   reader's socket in a folder beside the database file;
3. on PostgreSQL, every listening process: ``NOTIFY`` on :data:`CHANNEL`,
   which each reader LISTENs to on a connection of its own;
4. with Redis configured, every web process: a message to the channel-layer
   group :data:`GROUP`.

1 and 2 happen in the writer's thread just after its commit (a function call,
a non-blocking datagram).  3 and 4 leave it: one thread per process sends them,
at once after a quiet spell and at most once per FTT_LIVE_NOTIFY_DELAY_MS in a
stream of commits, NOTIFY on a connection of its own.  Commits do not send
NOTIFY themselves, because PostgreSQL holds a database-wide lock from a
notifying commit until its WAL flush ends, and commits that notify cannot share
a flush (many single poses a second would be bounded by it).  The exception is
a segment change (a mode switch, a leg started or stopped): rare, and what a
fleet view waits for, so its transaction NOTIFYs as well and PostgreSQL
delivers that at the commit, without waiting for the writer's process (a
collector on a busy robot) to get a core again for 3.  A wake-up lost (a
process that dies in between, a full socket queue) delays the readers by at
most one poll interval.
"""

import asyncio
import atexit
import functools
import hashlib
import logging
import os
import socket
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import psycopg
from channels.layers import get_channel_layer
from django.conf import settings
from django.db import connections, transaction
from django.db.models.signals import post_save

from common.sql import conninfo

logger = logging.getLogger(__name__)

GROUP = "ftt-live"
# PostgreSQL's LISTEN/NOTIFY channel of the feed.
CHANNEL = "ftt_live"
# After a failed wake-up the thread waits this long before it tries again.
RETRY = 1.0
# Seconds a process that ends waits for a wake-up being sent.
EXIT_WAIT = 2.0

# Readers in this process (one per event loop); each is thread-safe to call.
local_readers: set[Callable[[], None]] = set()


def _wake_local_readers() -> None:
    for wake in list(local_readers):
        try:
            wake()
        except RuntimeError:  # its event loop has just closed
            local_readers.discard(wake)
        except Exception:  # noqa: BLE001 - one reader's failure must not keep the others asleep
            logger.exception("live reader not woken")


# --- SQLite: a datagram per reader ---------------------------------------------------------

# A socket path must fit in sockaddr_un (108 bytes with its terminator).
_MAX_SOCKET_PATH = 100
# A listener's name in the folder: "/", a process id and an object id in hex.
_LISTENER_NAME = 1 + 7 + 1 + 12
_sender: socket.socket | None = None


def socket_folder(using: str = "default") -> Path | None:
    """Where SQLite readers of this database listen; None on other databases."""
    connection = connections[using]
    if connection.vendor != "sqlite":
        return None
    name = str(connection.settings_dict["NAME"])
    if not name or name == ":memory:" or name.startswith("file:"):
        return None
    folder = Path(f"{os.path.abspath(name)}.wake")
    if len(str(folder)) + _LISTENER_NAME > _MAX_SOCKET_PATH:
        # A database deep in the file system: its sockets go to a short folder
        # named by the database's path, which every process on it finds alike.
        digest = hashlib.sha256(str(folder).encode()).hexdigest()[:16]
        folder = Path(tempfile.gettempdir()) / f"ftt-wake-{digest}"
    return folder


def wake_sqlite_readers(folder: Path) -> None:
    """Send every reader listening in ``folder`` a datagram; forget dead ones."""
    global _sender
    try:
        paths = list(folder.iterdir())
    except FileNotFoundError:
        return  # nobody listens
    if _sender is None:
        _sender = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        _sender.setblocking(False)
    for path in paths:
        try:
            _sender.sendto(b"!", str(path))
        except (ConnectionRefusedError, FileNotFoundError):
            # Left by a process that died without closing: nobody reads it.
            path.unlink(missing_ok=True)
        except OSError:
            pass  # its queue is full, so that reader is awake anyway


class SqliteListener:
    """A reader's end: a datagram socket in the database's wake-up folder."""

    def __init__(self, folder: Path):
        folder.mkdir(mode=0o700, exist_ok=True)
        # In a shared temporary folder another account could have made it first.
        kept = folder.stat()
        if kept.st_uid != os.getuid() or kept.st_mode & 0o077:
            raise OSError(f"wake-up folder {folder} is not this account's own")
        self.path = folder / f"{os.getpid()}-{id(self):x}"
        if len(str(self.path)) > _MAX_SOCKET_PATH:
            raise OSError(f"wake-up socket path too long: {self.path}")
        self.socket = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.socket.setblocking(False)
        self.path.unlink(missing_ok=True)
        self.socket.bind(str(self.path))

    def fileno(self) -> int:
        return self.socket.fileno()

    def drain(self) -> None:
        """Read every waiting datagram: one wake-up covers them all."""
        try:
            while self.socket.recv(16):
                pass
        except BlockingIOError:
            pass

    def close(self) -> None:
        self.socket.close()
        self.path.unlink(missing_ok=True)


# --- PostgreSQL and Redis: one thread per process ------------------------------------------


class Sender:
    """Sends ``NOTIFY`` (PostgreSQL) and the channel-layer message (Redis) after
    every :meth:`poke`, at most once per ``delay`` and once for all pokes that
    arrive while it waits or sends.
    :meth:`poke` never blocks and never fails: the thread and its connection
    start with the first one."""

    def __init__(self, delay: float):
        self.delay = delay
        self._poked = threading.Event()
        self._lock = threading.Lock()
        # Held while the connection and the loop are used, by the thread or at exit.
        self._using = threading.RLock()
        self._connection = None
        # The thread's own event loop for the channel layer, kept across sends:
        # channels_redis keeps one connection per loop.
        self._loop: asyncio.AbstractEventLoop | None = None
        self._pid = None

    def poke(self) -> None:
        self._poked.set()
        # A forked child has the parent's state but not its thread.
        if self._pid == os.getpid():
            return
        with self._lock:
            if self._pid == os.getpid():
                return
            # A forked child must not use its parent's loop (its selector is shared).
            self._loop = None
            try:
                thread = threading.Thread(target=self._run, name="ftt-wakeup", daemon=True)
                thread.start()
            except RuntimeError as exc:  # the interpreter is shutting down
                logger.warning("live wake-up thread not started: %s", exc)
                return
            self._pid = os.getpid()

    def _run(self) -> None:
        sent = 0.0
        failing = False
        while True:
            self._poked.wait()
            # At once after a quiet spell; in a stream of commits, at most one
            # wake-up per delay, so that many commits share one.
            time.sleep(max(0.0, sent + self.delay - time.monotonic()))
            sent = time.monotonic()
            try:
                self._send()
            except Exception as exc:  # noqa: BLE001 - the readers poll meanwhile
                # Once per outage, not once per try: a robot's log must stay readable.
                if not failing:
                    logger.warning("live wake-up not sent: %s; trying again every %g s", exc, RETRY)
                    failing = True
                self._close()
                self._poked.set()
                time.sleep(RETRY)
            else:
                if failing:
                    logger.warning("live wake-ups are sent again")
                    failing = False

    def _send(self) -> None:
        with self._using:
            # Cleared before sending: a poke from now on gets a wake-up of its own.
            self._poked.clear()
            if connections["default"].vendor == "postgresql":
                if self._connection is None or self._connection.closed:
                    self._connection = psycopg.connect(conninfo(), autocommit=True)
                self._connection.execute(f"NOTIFY {CHANNEL}")
            if settings.REDIS_URL:
                layer = get_channel_layer()
                if layer is not None:
                    if self._loop is None:
                        self._loop = asyncio.new_event_loop()
                    self._loop.run_until_complete(layer.group_send(GROUP, {"type": "live.wake"}))

    def send_due_and_close(self) -> None:
        """Send a wake-up still due, then close the connection (a later poke opens
        another). At exit: a command that writes and ends at once (an import, a
        collector's last close) would otherwise take its wake-up with it, and the
        browsers would see the write only at their next poll."""
        if self._pid != os.getpid():
            return  # a forked child's copy: the connection is its parent's
        # Bounded: the thread may hang in a connect to an unreachable database.
        if not self._using.acquire(timeout=EXIT_WAIT):
            logger.warning("live wake-up not sent at exit: the database does not answer")
            return
        try:
            if self._poked.is_set():
                self._send()
            self._close()
        except Exception as exc:  # noqa: BLE001 - the readers poll meanwhile
            logger.warning("live wake-up not sent at exit: %s", exc)
        finally:
            self._using.release()

    def _close(self) -> None:
        with self._using:
            if self._connection is not None:
                self._connection.close()
                self._connection = None


_sender_thread = Sender(settings.FTT_LIVE_NOTIFY_DELAY_MS / 1000)
atexit.register(_sender_thread.send_due_and_close)


def send_due_and_close() -> None:
    _sender_thread.send_due_and_close()


# --- the hook ------------------------------------------------------------------------------


def _after_commit(using: str) -> None:
    if local_readers:
        _wake_local_readers()
    folder = socket_folder(using)
    if folder is not None:
        wake_sqlite_readers(folder)
    if connections[using].vendor == "postgresql" or settings.REDIS_URL:
        _sender_thread.poke()


def _on_feed_row(sender, instance, created, using=None, **kwargs) -> None:
    if created:
        using = using or "default"
        connection = connections[using]
        if instance.kind == sender.Kind.SEGMENT and connection.vendor == "postgresql":
            with connection.cursor() as cursor:
                cursor.execute(f"NOTIFY {CHANNEL}")
        # robust: a failed wake-up is logged, never raised into the committed write.
        transaction.on_commit(functools.partial(_after_commit, using), using=using, robust=True)


def connect() -> None:
    # A lazy sender: this module loads before the models do.
    post_save.connect(_on_feed_row, sender="events.Announcement", dispatch_uid="ftt-live-wakeup")
