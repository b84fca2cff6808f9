"""Wakes every web process's feed reader when a feed row commits.

Only a shortcut: the readers poll the feed anyway, so a lost wake-up costs at
most one poll interval.  It listens to the feed's rows (a post_save signal)
instead of being called by the writers, which sit in lower layers.

Three ways, whichever apply: on PostgreSQL a NOTIFY in the writer's own
transaction (delivered by the database at commit, to every listening process,
the collector's included); with Redis a message to the channel-layer group;
and in the writing process itself a direct call to its readers.
"""

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


def _on_feed_row(sender, instance, created, using=None, **kwargs) -> None:
    if not created:
        return
    connection = connections[using or "default"]
    if connection.vendor == "postgresql":
        # Notifications of one transaction are folded into one and sent at commit.
        with connection.cursor() as cursor:
            cursor.execute(f"NOTIFY {CHANNEL}")
    if getattr(settings, "REDIS_URL", ""):
        transaction.on_commit(_wake_other_processes, using=using)
    if local_readers:
        transaction.on_commit(_wake_local_readers, using=using)


def connect() -> None:
    # A lazy sender: this module loads before the models do.
    post_save.connect(_on_feed_row, sender="events.Announcement", dispatch_uid="ftt-live-wakeup")
