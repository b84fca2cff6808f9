"""Wakes every web process's feed reader when a feed row commits.

Only a shortcut: the readers poll the feed anyway, so a lost wake-up costs at
most one poll interval.  It listens to the feed's rows (a post_save signal)
instead of being called by the writers, which sit in lower layers.

Three ways, whichever apply: on PostgreSQL a NOTIFY in the writer's own
transaction (delivered by the database at commit, to every listening process,
the collector's included); with Redis a message to the channel-layer group;
and in the writing process itself a direct call to its readers.
"""

import functools
import logging
from collections.abc import Callable

from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from django.conf import settings
from django.db import connections, transaction
from django.db.models.signals import post_save

logger = logging.getLogger(__name__)

GROUP = "ftt-live"
# PostgreSQL's LISTEN/NOTIFY channel.
CHANNEL = "ftt_live"

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


def _after_commit(using: str) -> None:
    if getattr(settings, "REDIS_URL", ""):
        _wake_other_processes()
    if local_readers:
        _wake_local_readers()


def _announced_in_this_transaction(connection) -> bool:
    # Django keeps the on-commit callbacks per transaction and drops those of a
    # rolled-back savepoint, whose NOTIFY PostgreSQL drops too: so "our callback
    # is waiting" means exactly "this transaction has already notified".
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
    if connection.vendor == "postgresql":
        # Delivered by the database at commit, to every listening process.
        with connection.cursor() as cursor:
            cursor.execute(f"NOTIFY {CHANNEL}")
    transaction.on_commit(functools.partial(_after_commit, using), using=using)


def connect() -> None:
    # A lazy sender: this module loads before the models do.
    post_save.connect(_on_feed_row, sender="events.Announcement", dispatch_uid="ftt-live-wakeup")
