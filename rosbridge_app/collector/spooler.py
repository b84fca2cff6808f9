"""The spool thread: events from the ROS thread into the outbox on disk.

It renders pictures (PNG/JPEG) and appends events to the :class:`Outbox` a few
times a second; a mode switch, start or stop is appended at once.
"""

import logging
import queue
import threading
import time
from pathlib import Path

from django.conf import settings
from django.utils.translation import gettext

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.outbox import Outbox

log = logging.getLogger("ftt.collector")

SPOOL_INTERVAL = 0.05
BATCH = 500


def default_spool(name: str) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name)
    return Path(settings.DATA_DIR) / "collector" / f"{safe}.spool.sqlite3"


# What an operator waits to see: spooled at once, not after the batching window.
_URGENT = frozenset({ev.MODE, ev.START, ev.STOP})


class Spooler(threading.Thread):
    def __init__(self, events: queue.Queue, outbox: Outbox):
        super().__init__(name="ftt-spool", daemon=True)
        self.events, self.outbox = events, outbox
        self.stop = threading.Event()
        # Set after every append: the writer waits on it instead of sleeping.
        self.spooled = threading.Event()
        self.dropped = 0

    def run(self) -> None:
        while not self.stop.is_set() or not self.events.empty():
            self.spool_once(timeout=SPOOL_INTERVAL)

    def spool_once(self, timeout: float) -> int:
        """Positions wait up to ``timeout`` to share one append; a mode switch,
        start or stop ends the wait, so it reaches the database without it."""
        batch = []
        deadline = time.monotonic() + timeout
        while len(batch) < BATCH:
            try:
                event = self.events.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                break
            try:
                batch.append(event.prepare())
            except Exception as exc:
                self.dropped += 1
                log.warning(gettext("dropped a %s that cannot be converted: %s"), event.kind, exc)
            if event.kind in _URGENT:
                deadline = 0.0  # take only what is already queued
        if batch:
            while True:
                try:
                    self.outbox.append(batch)
                    break
                except Exception:
                    # The disk is our last resort: keep trying rather than drop.
                    log.exception("cannot write the spool %s; retrying", self.outbox.path)
                    time.sleep(1.0)
            self.spooled.set()
        return len(batch)
