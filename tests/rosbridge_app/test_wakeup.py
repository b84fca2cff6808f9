"""A transaction that writes many feed rows wakes the readers once."""

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
