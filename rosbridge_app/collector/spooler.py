"""The spool thread: events from the ROS thread into the spool on disk.

It renders pictures (PNG/JPEG) and appends events to the :class:`Spool` a few
times a second; a mode switch, start or stop is appended at once.  When the
disk budget says so (disk_guard.py), camera frames are dropped unless the
database answers, and when the spool cannot be written events are held in
memory (held.py) instead; they go
back to the spool, in order, before anything newer, once it has room.
"""

import logging
import queue
import threading
import time
from pathlib import Path

from django.conf import settings
from django.utils.translation import gettext

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.disk_guard import FULL, TIGHT, DiskGuard
from rosbridge_app.collector.held import Held
from rosbridge_app.collector.spool import Spool, SpoolFull

log = logging.getLogger("ftt.collector")

SPOOL_INTERVAL = 0.05
BATCH = 500


def default_spool(name: str) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name)
    return Path(settings.DATA_DIR) / "collector" / f"{safe}.spool.sqlite3"


class Spooler(threading.Thread):
    def __init__(
        self,
        events: queue.Queue,
        spool: Spool,
        guard: DiskGuard | None = None,
        database_ok=lambda: False,
    ):
        super().__init__(name="ftt-spool", daemon=True)
        self.events, self.spool = events, spool
        self.guard = guard or DiskGuard(spool.path)
        self.guard.reusable = spool.reusable
        spool.free_reserve = self.guard.release_reserve
        self.held = Held(self.guard, database_ok)
        self.stop = threading.Event()
        # Set after every append: the writer waits on it instead of sleeping.
        self.spooled = threading.Event()
        # Set after a segment change (mode, start, stop) was spooled: the writer
        # stores it before its periodic chores.
        self.urgent = threading.Event()
        self.dropped = 0

    def run(self) -> None:
        while not self.stop.is_set() or not self.events.empty():
            self.spool_once(timeout=SPOOL_INTERVAL)

    def spool_once(self, timeout: float) -> int:
        """Positions wait up to ``timeout`` to share one append; a mode switch,
        start or stop ends the wait, so it reaches the database without it."""
        batch = []
        urgent = False
        deadline = time.monotonic() + timeout
        while len(batch) < BATCH:
            try:
                event = self.events.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                break
            if event.kind == ev.IMAGE and self.guard.level >= TIGHT and not self.held.database_ok():
                self.guard.count("frames")  # before rendering: the first thing given up
            else:
                try:
                    batch.append(event.prepare())
                except Exception as exc:
                    self.dropped += 1
                    log.warning(
                        gettext("dropped a %s that cannot be converted: %s"), event.kind, exc
                    )
            if event.kind in ev.SEGMENT_CHANGES:
                urgent = True
                deadline = 0.0  # take only what is already queued
        if batch or len(self.held):
            self._store(batch)
            if urgent:
                self.urgent.set()
            self.spooled.set()
        return len(batch)

    def _store(self, batch: list) -> None:
        """To the spool if it has room (what memory holds first), else to memory."""
        size = sum(len(e.blob or b"") + 200 for e in batch)
        if self.guard.check(size) < FULL:
            self.held.flush_skipped()
            with self.held.lock:
                back = list(self.held.events)
                if back and self._append(back):
                    self.held.remove(back)
            if not len(self.held) and (not batch or self._append(batch)):
                return
        for event in batch:
            self.held.add(event)

    def _append(self, events: list) -> bool:
        try:
            self.spool.append(events)
            return True
        except SpoolFull as exc:
            self.guard.failed(exc)
        except Exception as exc:  # a spool that cannot be written at all: memory still can
            if self.guard.level < FULL:
                log.error(gettext("cannot write the spool %s: %s"), self.spool.path, exc)
            self.guard.failed(exc)
        return False
