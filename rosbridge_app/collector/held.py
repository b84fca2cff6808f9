"""What the collector keeps in memory while the spool cannot be written
(disk_guard.py decides when).

Within a bound, in this order of importance: mode switches and segment
changes (start, stop) always; positions thinned to the report's resolution
(one per ``REPORT_PERIOD`` per kind, plus the last one before and the first
one after each segment change, so every segment's track keeps its ends),
all of them while the database answers (nothing waits for the disk then); the
latest map only. Camera frames are kept only while the database answers
(within ``MAX_FRAME_BYTES``); else they are dropped. The writer takes these events
straight to the database once it is reachable (collector/replay.py), or the
spool takes them back once the disk has room; both in order.
"""

import threading
from collections import deque

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.disk_guard import DiskGuard
from rosbridge_app.collector.events import Event

# The report draws a segment's track from positions a second apart at most
# (at walking pace a metre): finer is not seen on its map or in its figures.
REPORT_PERIOD = 1.0
# A day of thinned GPS and local positions; more are counted and dropped.
MAX_POSITIONS = 200_000
# Frames wait in memory only for a database that answers: a few seconds of
# camera at most, however large the frames.
MAX_FRAME_BYTES = 64 * 1024 * 1024
_POSITIONS = frozenset({ev.GPS_FIX, ev.LOCAL_POSE})
_CHANGES = frozenset({ev.MODE, ev.START, ev.STOP})


class Held:
    """``database_ok`` tells whether the database answers: the writer then takes
    what is held straight to it, so positions are kept at full rate."""

    def __init__(self, guard: DiskGuard, database_ok=lambda: False):
        self.guard = guard
        self.database_ok = database_ok
        self.events: deque[Event] = deque()
        # Held by whoever moves events out (the writer or the spool thread),
        # so the two never take the same ones.
        self.lock = threading.RLock()
        self._positions = 0
        self._frame_bytes = 0
        self._appended_at: dict[str, float] = {}
        self._skipped: dict[str, Event] = {}  # the newest position not kept, per kind

    def __len__(self) -> int:
        return len(self.events)

    def add(self, event: Event) -> None:
        with self.lock:
            kind = event.kind
            if kind in _CHANGES:
                # The segment's last position ends its track; the next one starts anew.
                for skipped in self._skipped.values():
                    self._append(skipped)
                self._skipped.clear()
                self._appended_at.clear()
                self._append(event)
            elif kind in _POSITIONS:
                self._add_position(event)
            elif kind == ev.IMAGE:
                size = len(event.blob or b"")
                if self.database_ok() and self._frame_bytes + size <= MAX_FRAME_BYTES:
                    self._append(event)
                else:
                    self.guard.count("frames")
            elif kind == ev.MAP:
                older = [e for e in self.events if e.kind == ev.MAP]
                for e in older:
                    self.events.remove(e)
                self.guard.count("maps", len(older))
                self._append(event)
            else:
                self._append(event)

    def _add_position(self, event: Event) -> None:
        t = event.at.timestamp()
        appended = self._appended_at.get(event.kind)
        thinned = appended is not None and t - appended < REPORT_PERIOD and not self.database_ok()
        if self._positions >= MAX_POSITIONS or thinned:
            dropped = self._skipped.get(event.kind)
            if dropped is not None:
                self.guard.count("positions")
            self._skipped[event.kind] = event
            return
        self._skipped.pop(event.kind, None)
        self._appended_at[event.kind] = t
        self._append(event)

    def _append(self, event: Event) -> None:
        if event.kind in _POSITIONS:
            self._positions += 1
        elif event.kind == ev.IMAGE:
            self._frame_bytes += len(event.blob or b"")
        self.events.append(event)

    def peek(self, limit: int, maps: bool = True) -> list[Event]:
        """The oldest events (maps left out unless ``maps``); call with ``lock`` held."""
        out = []
        for event in self.events:
            if len(out) >= limit:
                break
            if maps or event.kind != ev.MAP:
                out.append(event)
        return out

    def remove(self, taken: list[Event]) -> None:
        """Call with ``lock`` held, after ``taken`` (from ``peek``) is stored."""
        gone = {id(e) for e in taken}
        self.events = deque(e for e in self.events if id(e) not in gone)
        self._positions -= sum(1 for e in taken if e.kind in _POSITIONS)
        self._frame_bytes -= sum(len(e.blob or b"") for e in taken if e.kind == ev.IMAGE)

    def flush_skipped(self) -> None:
        """The newest positions not kept go in too (nothing more follows them)."""
        with self.lock:
            for skipped in self._skipped.values():
                self._append(skipped)
            self._skipped.clear()
