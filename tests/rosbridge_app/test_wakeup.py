"""Wake-ups: one per transaction, and across processes on SQLite."""

import socket

import pytest
from django.db import connection, transaction
from django.test.utils import CaptureQueriesContext

from events import feed
from rosbridge_app import wakeup

pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture
def woken():
    calls = []

    def reader():
        calls.append(1)

    wakeup.local_readers.add(reader)
    yield calls
    wakeup.local_readers.discard(reader)


def notifies(queries) -> int:
    return sum(q["sql"].startswith("NOTIFY") for q in queries.captured_queries)


def test_a_transaction_of_many_feed_rows_wakes_once(woken):
    with CaptureQueriesContext(connection) as queries:
        with transaction.atomic():
            for i in range(5):
                feed.record("poses", payload={"count": i})
            assert woken == []  # nothing before the commit
    assert woken == [1]
    assert notifies(queries) == (1 if connection.vendor == "postgresql" else 0)
    # The next transaction wakes again.
    feed.record("poses")
    assert woken == [1, 1]


def test_a_rolled_back_savepoint_does_not_take_the_wake_up_with_it(woken):
    with CaptureQueriesContext(connection) as queries:
        with transaction.atomic():
            try:
                with transaction.atomic():
                    feed.record("poses")
                    raise RuntimeError("undo")
            except RuntimeError:
                pass
            feed.record("poses")
    assert woken == [1]
    # PostgreSQL dropped the first NOTIFY with the savepoint: a second one was sent.
    assert notifies(queries) == (2 if connection.vendor == "postgresql" else 0)


def test_a_rolled_back_transaction_wakes_nobody(woken):
    with pytest.raises(RuntimeError), transaction.atomic():
        feed.record("poses")
        raise RuntimeError("undo")
    assert woken == []


def test_sqlite_readers_are_woken_and_dead_ones_forgotten(tmp_path):
    folder = tmp_path / "ftt.sqlite3.wake"
    alive = wakeup.SqliteListener(folder)
    # A reader killed before it could clean up leaves its socket file behind.
    dead = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    dead.bind(str(folder / "dead"))
    dead.close()
    try:
        wakeup._wake_sqlite_readers(folder)
        wakeup._wake_sqlite_readers(folder)
        assert alive.socket.recv(16) == b"!"
        alive.drain()
        with pytest.raises(BlockingIOError):
            alive.socket.recv(16)
        assert sorted(p.name for p in folder.iterdir()) == [alive.path.name]
    finally:
        alive.close()
    assert not alive.path.exists()
