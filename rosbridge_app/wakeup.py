"""Wakes every web process's feed reader when a feed row commits.

Only a shortcut: the readers poll the feed anyway, so a lost wake-up costs at
most one poll interval.  It listens to the feed's rows (a post_save signal)
instead of being called by the writers, which sit in lower layers.

Four ways, whichever apply: on PostgreSQL a NOTIFY from a trigger on the
feed's table (events.feed.CHANNEL; delivered by the database at commit, to
every listening process, the collector's included); with Redis a message to the channel-layer group;
on SQLite a datagram to every reader's socket in a folder beside the database
file (the collector and the web server are separate processes that share
nothing else); and in the writing process itself a direct call to its readers.
"""

import functools
import logging
import os
import socket
from collections.abc import Callable
from pathlib import Path

from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from django.conf import settings
from django.db import connections, transaction
from django.db.models.signals import post_save

logger = logging.getLogger(__name__)

GROUP = "ftt-live"

# Readers in this process (one per event loop); each is thread-safe to call.
local_readers: set[Callable[[], None]] = set()


def _wake_other_processes() -> None:
    try:
        layer = get_channel_layer()
        if layer is not None:
            async_to_sync(layer.group_send)(GROUP, {"type": "live.wake"})
    except Exception as exc:  # noqa: BLE001 - never fail a committed write
        logger.debug("live wake-up not sent: %s", exc)


def _wake_local_readers() -> None:
    for wake in list(local_readers):
        try:
            wake()
        except RuntimeError:  # its event loop has just closed
            local_readers.discard(wake)


# A socket path must fit in sockaddr_un (108 bytes with its terminator).
_MAX_SOCKET_PATH = 100
_sender: socket.socket | None = None


def socket_folder(using: str = "default") -> Path | None:
    """Where SQLite readers of this database listen; None on other databases."""
    connection = connections[using]
    if connection.vendor != "sqlite":
        return None
    name = str(connection.settings_dict["NAME"])
    if not name or name == ":memory:" or name.startswith("file:"):
        return None
    return Path(f"{name}.wake")


def _wake_sqlite_readers(folder: Path) -> None:
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


def _after_commit(using: str) -> None:
    if getattr(settings, "REDIS_URL", ""):
        _wake_other_processes()
    folder = socket_folder(using)
    if folder is not None:
        _wake_sqlite_readers(folder)
    if local_readers:
        _wake_local_readers()


def _announced_in_this_transaction(connection) -> bool:
    # Django keeps the on-commit callbacks per transaction and drops those of a
    # rolled-back savepoint: so "our callback is waiting" means exactly "this
    # transaction will wake the readers".
    return any(
        getattr(func, "func", None) is _after_commit for _, func, *_ in connection.run_on_commit
    )


def _on_feed_row(sender, instance, created, using=None, **kwargs) -> None:
    """One wake-up per transaction, however many feed rows it writes (a pose
    batch, a collector batch with a mode switch and its track)."""
    if not created:
        return
    using = using or "default"
    connection = connections[using]
    if connection.in_atomic_block and _announced_in_this_transaction(connection):
        return
    # PostgreSQL's listeners hear the table's trigger; these are the other ways.
    transaction.on_commit(functools.partial(_after_commit, using), using=using)


def connect() -> None:
    # A lazy sender: this module loads before the models do.
    post_save.connect(_on_feed_row, sender="events.Announcement", dispatch_uid="ftt-live-wakeup")
