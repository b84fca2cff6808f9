"""The spool thread batches positions but lets a mode switch through at once."""

import queue
import time
from datetime import UTC, datetime

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.spool import Spool
from rosbridge_app.collector.spooler import Spooler

WINDOW = 60.0  # far longer than any machine needs for the rest


def test_a_mode_switch_does_not_wait_for_the_batching_window(tmp_path):
    events = queue.Queue()
    spooler = Spooler(events, Spool(tmp_path / "spool.sqlite3"))
    now = datetime.now(UTC)
    events.put(Event(ev.GPS_FIX, now, {"lon": 7.0, "lat": 50.0}))
    events.put(Event(ev.MODE, now, {"mode": "auto"}))
    started = time.monotonic()
    assert spooler.spool_once(timeout=WINDOW) == 2
    assert time.monotonic() - started < WINDOW / 2
    assert [e.kind for _, e in spooler.spool.peek()] == [ev.GPS_FIX, ev.MODE]
    assert spooler.spooled.is_set()  # the writer is woken
    assert spooler.urgent.is_set()  # and stores the switch before its chores


def test_positions_share_one_append_within_the_window(tmp_path):
    events = queue.Queue()
    spooler = Spooler(events, Spool(tmp_path / "spool.sqlite3"))
    now = datetime.now(UTC)
    for i in range(3):
        events.put(Event(ev.GPS_FIX, now, {"lon": 7.0 + i, "lat": 50.0}))
    assert spooler.spool_once(timeout=0.2) == 3
    assert len(spooler.spool) == 3
    assert not spooler.urgent.is_set()
