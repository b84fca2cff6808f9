"""Test cases as the comparison page offers them: those with an area for the place
search, those with a planned route for the route comparison."""

import json

from events.models import TestCase


def test_case_areas() -> list[dict]:
    """Each test case with an area: id, names, its test event and the area as GeoJSON."""
    cases = TestCase.objects.filter(area__isnull=False).select_related("test_event")
    return [
        {
            "id": case.pk,
            "key": case.key,
            "title": case.title,
            "test_event": case.test_event_id,
            "area": json.loads(case.area.geojson),
        }
        for case in cases.order_by("test_event_id", "key")
    ]


def test_case_routes() -> list[dict]:
    """Each test case with a planned route: id, names and its test event."""
    cases = TestCase.objects.filter(route__isnull=False).order_by("test_event_id", "key")
    return list(cases.values("id", "key", "title", "test_event"))
