"""Filtering lists by parent, open state, time range, mode and bounding box."""

from datetime import timedelta

import pytest

from common import roles
from events.models import SegmentType
from events.services import logs, segments
from events.services.segments import GpsPosition


@pytest.fixture
def viewer(api_client):
    client = api_client(roles.VIEWER)

    def ids(path, **query):
        response = client.get(path, query)
        assert response.status_code == 200, response.content
        return sorted(row["id"] for row in response.json()["results"])

    return ids


def test_open_and_parent_filters(viewer, leg):
    first_leg = leg
    second_leg = logs.create_leg(shift=leg.shift)  # closes the first
    other_event = logs.create_test_event(location="elsewhere")
    assert viewer("/api/legs/", open="true") == [second_leg.pk]
    assert viewer("/api/legs/", open="false") == [first_leg.pk]
    assert viewer("/api/legs/", shift=leg.shift_id) == [first_leg.pk, second_leg.pk]
    assert viewer("/api/legs/", test_event=other_event.pk) == []
    assert viewer("/api/shifts/", test_event=leg.shift.test_event_id) == [leg.shift_id]
    assert viewer("/api/test-events/", open="1") == sorted(
        [leg.shift.test_event_id, other_event.pk]
    )


def test_time_range_on_start(viewer, leg):
    later = logs.create_leg(shift=leg.shift, at=leg.start + timedelta(minutes=5))
    middle = (leg.start + timedelta(minutes=1)).isoformat()
    assert viewer("/api/legs/", start_after=middle) == [later.pk]
    assert viewer("/api/legs/", start_before=middle) == [leg.pk]


def test_segment_filters_mode_master_and_bbox(viewer, leg):
    auto = segments.report_mode(leg, SegmentType.AUTO, gps=GpsPosition(7.0, 50.0)).master
    ito = segments.report_mode(leg, SegmentType.ITO, gps=GpsPosition(-70.0, -30.0)).master
    child = ito.children.get()
    assert viewer("/api/segments/", leg=leg.pk, master="true") == [auto.pk, ito.pk]
    assert viewer("/api/segments/", master="false") == [child.pk]
    assert viewer("/api/segments/", mode="auto") == [auto.pk]
    assert viewer("/api/segments/", parent=ito.pk) == [child.pk]
    assert viewer("/api/segments/", in_bbox="6,49,8,51") == [auto.pk]
    # The child starts where its master starts.
    assert viewer("/api/segments/", in_bbox="-71,-31,-69,-29") == [ito.pk, child.pk]
    assert viewer("/api/segments/", open="true", leg=leg.pk) == [ito.pk, child.pk]


def test_modified_after_lists_only_what_changed_since(viewer, api_client, leg):
    """A script that mirrors FTT asks for what changed since its last visit."""
    from django.utils import timezone

    ito = segments.report_mode(leg, SegmentType.ITO).master
    child = ito.children.get()
    cut = timezone.now().isoformat()
    assert viewer("/api/segments/", modified_after=cut) == []
    assert viewer("/api/legs/", modified_after=cut) == []
    segments.annotate_segment(child, obstacle="rock")
    assert viewer("/api/segments/", modified_after=cut) == [child.pk]
    row = api_client(roles.VIEWER).get(f"/api/segments/{child.pk}/").json()
    assert row["annotated"] is not None and row["modified"] >= row["annotated"]
