"""Wake-ups: after the commit of a feed row, never for a rolled-back one, and
across processes (NOTIFY on PostgreSQL, datagrams on SQLite)."""

import contextlib
import logging
import shutil
import socket
import tempfile
import threading
import time
from pathlib import Path

import psycopg
import pytest
from django.db import connection, transaction

from common.sql import conninfo
from events import feed
from live import wakeup
from tests.support.ros import database_url
from tests.support.sites import Site

# On SpatiaLite too: LISTEN/NOTIFY on PostgreSQL, the writer's signal on SpatiaLite.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db(transaction=True)]


@pytest.fixture
def woken():
    calls = []

    def reader():
        calls.append(1)

    wakeup.local_readers.add(reader)
    yield calls
    wakeup.local_readers.discard(reader)


@contextlib.contextmanager
def listening():
    """Notifications of the feed's channel heard by another session (PostgreSQL;
    elsewhere none), as a web process's listener hears them."""
    heard = []
    if connection.vendor != "postgresql":
        yield heard
        return
    with psycopg.connect(conninfo(), autocommit=True) as listener:
        listener.execute(f"LISTEN {wakeup.CHANNEL}")
        yield heard
        # Sent by the writing process's wake-up thread just after the commit.
        heard.extend(listener.notifies(timeout=2.0, stop_after=10))


def test_a_transaction_of_many_feed_rows_wakes_the_readers_after_its_commit(woken):
    with listening() as heard:
        with transaction.atomic():
            for i in range(5):
                feed.append("poses", payload={"count": i})
            assert woken == []  # nothing before the commit
        assert woken != []
    # The wake-up thread sends one NOTIFY for the commits of a few milliseconds.
    assert len(heard) == (1 if connection.vendor == "postgresql" else 0)


def test_a_rolled_back_savepoint_does_not_take_the_wake_up_with_it(woken):
    with listening() as heard:
        with transaction.atomic():
            try:
                with transaction.atomic():
                    feed.append("poses")
                    raise RuntimeError("undo")
            except RuntimeError:
                pass
            assert woken == []
            feed.append("poses")
        assert woken != []
    assert len(heard) == (1 if connection.vendor == "postgresql" else 0)


def test_a_rolled_back_feed_row_notifies_nobody():
    with listening() as heard:
        with pytest.raises(RuntimeError), transaction.atomic():
            feed.append("poses")
            raise RuntimeError("undo")
    assert heard == []


def test_a_reader_that_fails_does_not_fail_the_committed_write(woken):
    def broken():
        raise ValueError("a reader's bug")

    wakeup.local_readers.add(broken)
    try:
        row = feed.append("poses")
    finally:
        wakeup.local_readers.discard(broken)
    assert woken != []  # the other readers are woken all the same
    assert [r.pk for r in feed.after(row.pk - 1)] == [row.pk]


def test_a_rolled_back_transaction_wakes_nobody(woken):
    with pytest.raises(RuntimeError), transaction.atomic():
        feed.append("poses")
        raise RuntimeError("undo")
    assert woken == []


def test_sqlite_readers_are_woken_and_dead_ones_forgotten():
    # A socket path has at most 107 bytes, which an xdist worker's tmp_path nearly
    # fills; a data folder of FTT's is short.
    folder = Path(tempfile.mkdtemp(prefix="ftt-")) / "ftt.sqlite3.wake"
    alive = wakeup.SqliteListener(folder)
    # A reader killed before it could clean up leaves its socket file behind.
    dead = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    dead.bind(str(folder / "dead"))
    dead.close()
    try:
        wakeup.wake_sqlite_readers(folder)
        wakeup.wake_sqlite_readers(folder)
        assert alive.socket.recv(16) == b"!"
        alive.drain()
        with pytest.raises(BlockingIOError):
            alive.socket.recv(16)
        assert sorted(p.name for p in folder.iterdir()) == [alive.path.name]
    finally:
        alive.close()
    assert not alive.path.exists()
    shutil.rmtree(folder.parent)


def test_wake_ups_that_cannot_be_sent_are_logged_once_per_outage(monkeypatch, caplog):
    monkeypatch.setattr(wakeup, "RETRY", 0.01)
    caplog.set_level(logging.INFO, "live.wakeup")
    sent = [threading.Event(), threading.Event()]
    tries = []

    class Outage(wakeup.Sender):
        def _send(self):
            self._poked.clear()
            tries.append(1)
            if len(tries) <= 5:
                raise psycopg.OperationalError("connection refused")
            sent[len(tries) - 6].set()

    sender = Outage(delay=0)
    sender.poke()
    assert sent[0].wait(10)
    # The thread logs after a send returns: the next send comes after that line.
    sender.poke()
    assert sent[1].wait(10)
    lines = [r.getMessage() for r in caplog.records if r.name == "live.wakeup"]
    assert lines == [
        "live wake-up not sent: connection refused; trying again every 0.01 s",
        "live wake-ups are sent again",
    ]


@pytest.mark.postgis_only
def test_a_segment_change_is_heard_at_its_commit_without_the_writers_thread(monkeypatch):
    # A collector starved of CPU sends its thread's NOTIFY late: a mode switch
    # must not wait for it.  Other rows still do (their commits share a flush).
    monkeypatch.setattr(wakeup._sender_thread, "poke", lambda: None)
    with psycopg.connect(conninfo(), autocommit=True) as listener:
        listener.execute(f"LISTEN {wakeup.CHANNEL}")
        with transaction.atomic():
            feed.append("segment", payload={"segment": 1})
            feed.append("poses", payload={"count": 1})
            before_commit = list(listener.notifies(timeout=0.3, stop_after=1))
        at_commit = list(listener.notifies(timeout=2.0, stop_after=1))
        feed.append("poses", payload={"count": 2})
        for_poses_alone = list(listener.notifies(timeout=0.5, stop_after=1))
        with pytest.raises(RuntimeError), transaction.atomic():
            feed.append("segment", payload={"segment": 2})
            raise RuntimeError("undo")
        for_rolled_back = list(listener.notifies(timeout=0.5, stop_after=1))
    assert (len(before_commit), len(at_commit)) == (0, 1)
    assert for_poses_alone == [] and for_rolled_back == []


@pytest.mark.postgis_only
def test_a_command_that_writes_and_ends_at_once_still_wakes_the_browsers(tmp_path):
    # Two commits in a row: the first is sent at once, the second is due only
    # after the delay (a minute here), so the command has ended before it.
    site = Site(tmp_path, FTT_DATABASE_URL=database_url(connection.settings_dict),
                FTT_LIVE_NOTIFY_DELAY_MS="60000", FTT_REDIS_URL="")  # fmt: skip
    with psycopg.connect(conninfo(), autocommit=True) as listener:
        listener.execute(f"LISTEN {wakeup.CHANNEL}")
        site.python(
            "from events import feed\n"
            "feed.append('poses', payload={'count': 1})\n"
            "feed.append('poses', payload={'count': 2})\n"
        )
        heard = list(listener.notifies(timeout=5.0, stop_after=2))
    assert len(heard) == 2


def test_wake_ups_through_redis_share_one_connection(redis_layer):
    def published() -> int:
        return redis_layer.info("commandstats").get("cmdstat_publish", {}).get("calls", 0)

    sender = wakeup.Sender(delay=0)
    try:
        connected = redis_layer.info("stats")["total_connections_received"]
        for _ in range(8):
            before = published()
            sender.poke()
            deadline = time.monotonic() + 10
            while published() == before and time.monotonic() < deadline:
                time.sleep(0.01)
            assert published() > before, "no wake-up reached Redis"
        # The test's own INFO calls reuse its client's connection: only the sender's count.
        opened = redis_layer.info("stats")["total_connections_received"] - connected
        assert opened <= 1, f"{opened} connections for 8 wake-ups"
    finally:
        sender.send_due_and_close()
