"""Segment events carry the rows they changed, read in a fixed number of queries."""

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events import feed
from events.models import Announcement
from events.services import logs, segments
from live.consumers import _attach_segments, as_message

pytestmark = pytest.mark.django_db


def segment_events(after: int) -> list[dict]:
    rows = [as_message(e) for e in feed.after(after, 1000)]
    return [r for r in rows if r["kind"] == Announcement.Kind.SEGMENT]


def switch(leg, modes: str) -> None:
    for mode in modes.split():
        segments.report_mode(leg, mode)


def queries_to_attach(rows: list[dict]) -> int:
    with CaptureQueriesContext(connection) as queries:
        _attach_segments(rows)
    return len(queries)


def test_many_switches_on_two_legs_cost_as_few_queries_as_one(leg, shift):
    start = feed.bounds()[1]
    switch(leg, "ito")
    few = segment_events(start)
    start = feed.bounds()[1]
    switch(leg, "auto ito auto ito auto ito")
    other = logs.create_leg(shift=shift)  # closes `leg`
    switch(other, "ito auto ito auto ito auto")
    many = segment_events(start)
    assert len(few) == 1 and len(many) >= 12
    assert queries_to_attach(many) == queries_to_attach(few) == 4
    # Each event still brings what it changed: the new master, the master it
    # closed and the reason under that one, named as the report names them.
    last = many[-1]
    assert last["leg"] == other.pk
    kinds = sorted((row["segment_type"], row["parent"] is None) for row in last["segments"])
    assert kinds == [("auto", True), ("ito", False), ("ito", True)]
    assert sorted(last["labels"].values()) == [
        f"Leg {other.number} · #5",
        f"Leg {other.number} · #5.1",
        f"Leg {other.number} · #6",
    ]
