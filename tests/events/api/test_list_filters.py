"""The lists' filters: every ancestor filters notes as it filters the rows below
it, and a parameter a list does not know is a 400 naming it, never a list of
every row."""

import pytest

from common import roles
from events.services import logs, notes
from tests.support.modes import start_auto


@pytest.fixture
def two_events_notes(leg, other_leg, vehicle):
    """A note in each of two shifts of one event, and one in another event."""
    here = notes.add_note(start_auto(leg), text="here")
    beside = notes.add_note(start_auto(other_leg), text="beside")
    elsewhere_shift = logs.create_shift(
        test_event=logs.create_test_event(location="Elsewhere"), vehicle=vehicle
    )
    elsewhere = notes.add_note(start_auto(logs.create_leg(shift=elsewhere_shift)), text="there")
    return {"here": here, "beside": beside, "elsewhere": elsewhere, "leg": leg}


def texts(client, **query):
    answer = client.get("/api/notes/", query)
    assert answer.status_code == 200, answer.content
    return sorted(row["text"] for row in answer.json()["results"])


def test_notes_are_filtered_by_test_event_and_shift(api_client, two_events_notes):
    client = api_client(roles.VIEWER)
    leg = two_events_notes["leg"]
    assert texts(client) == ["beside", "here", "there"]
    assert texts(client, test_event=leg.shift.test_event_id) == ["beside", "here"]
    assert texts(client, shift=leg.shift_id) == ["here"]
    assert texts(client, leg=leg.pk, page_size=10) == ["here"]


@pytest.mark.parametrize(
    ("path", "query"),
    [
        ("/api/notes/", {"test_events": "1"}),
        ("/api/notes/", {"vehicle": "1"}),
        ("/api/poses/", {"sgment": "1"}),
        ("/api/segments/", {"within_area": "x"}),
        ("/api/segments/found/", {"reasons": "safety"}),
    ],
)
def test_an_unknown_filter_is_refused_by_name(api_client, db, path, query):
    answer = api_client(roles.VIEWER).get(path, query)
    assert answer.status_code == 400
    (name,) = query
    assert "no such filter" in " ".join(answer.json()["errors"][name])


def test_paging_format_box_and_file_kind_are_known(api_client, two_events_notes):
    client = api_client(roles.VIEWER)
    assert (
        client.get("/api/notes/", {"page": 1, "page_size": 5, "format": "json"}).status_code == 200
    )
    box = {"in_bbox": "7,50,8,51", "master": "true"}
    assert client.get("/api/segments/", box).status_code == 200
    assert client.get("/api/poses/", {"in_bbox": "7,50,8,51"}).status_code == 200
    assert client.get("/api/segments/found/", {"as": "csv"}).status_code == 200
