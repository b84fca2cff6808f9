"""List endpoints of the log hierarchy and configuration run a fixed number of queries."""

import itertools

import pytest

from events.models import (
    ItoReason,
    Performer,
    Personnel,
    PoseSource,
    SegmentType,
    Vehicle,
    Weather,
)
from events.services import logs, notes, segments
from tests.support.api import LIST_QUERIES, assert_constant_queries, post_counting_queries

counter = itertools.count()


def _test_events(n, leg):
    for _ in range(n):
        logs.create_test_event(location=f"site {next(counter)}")


def _shifts(n, leg):
    for _ in range(n):
        logs.create_shift(test_event=leg.shift.test_event, vehicle=leg.shift.vehicle)


def _legs(n, leg):
    shift = leg.shift.test_event.shifts.filter(end__isnull=True).first()
    for _ in range(n):
        logs.create_leg(shift=shift)


def _segments(n, leg):
    for i in range(n):
        segments.report_mode(leg, SegmentType.ITO if i % 2 else SegmentType.AUTO)


def _notes(n, leg):
    segment = segments.new_manual_segment(leg)
    author = Personnel.objects.first()
    for i in range(n):
        notes.add_note(segment, text=f"note {i}", author=author)


def _configuration(model, constant=None, **fields):
    def add(n, leg):
        for _ in range(n):
            i = next(counter)
            model.objects.create(**{k: f"{v}{i}" for k, v in fields.items()}, **(constant or {}))

    return add


CASES = {
    "/api/test-events/": _test_events,
    "/api/shifts/": _shifts,
    "/api/legs/": _legs,
    "/api/segments/": _segments,
    "/api/notes/": _notes,
    "/api/personnel/": _configuration(Personnel, name="p"),
    "/api/performers/": _configuration(Performer, institution="i"),
    "/api/vehicles/": _configuration(Vehicle, key="v", short_description="v"),
    "/api/pose-sources/": _configuration(PoseSource, key="s", short_description="s"),
    # Catalogues are not paginated: no count query.
    "/api/weather/": _configuration(Weather, key="w", short_description="w"),
    "/api/ito-reasons/": _configuration(
        ItoReason, {"color": "10,20,30"}, key="r", short_description="r"
    ),
}


@pytest.mark.parametrize("url", CASES)
def test_list_queries_do_not_grow_with_rows(url, api_client, django_assert_max_num_queries, leg):
    assert_constant_queries(
        api_client,
        django_assert_max_num_queries,
        f"{url}?page_size=1000",
        lambda n: CASES[url](n, leg),
        most=LIST_QUERIES,
    )


def test_a_robot_costs_one_query_more_than_an_operator_until_its_vehicles_are_kept(
    api_client, robot_client, vehicle, leg
):
    """The robot's vehicles, read on its first request and kept for the next ones
    (like both clients' tokens); the leg's vehicle comes with the leg."""
    segments.report_mode(leg, SegmentType.AUTO)  # each client switches AUTO -> ITO -> AUTO
    counts = {}
    for name, client in (("operator", api_client("operator")), ("robot", robot_client(vehicle))):
        for mode in (SegmentType.ITO, SegmentType.AUTO):
            body = {"mode": mode}
            response, every, _ = post_counting_queries(client, f"/api/legs/{leg.pk}/mode/", body)
            assert response.status_code == 201, response.content
            counts[name, mode] = len(every)
    assert counts["robot", SegmentType.ITO] == counts["operator", SegmentType.ITO] + 1, counts
    assert counts["robot", SegmentType.AUTO] == counts["operator", SegmentType.AUTO], counts
    assert counts["operator", SegmentType.AUTO] < counts["operator", SegmentType.ITO], counts
