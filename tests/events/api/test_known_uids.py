"""A uid already stored is a retry only for its own row's owner (issue 42, defect 1):
another note's, test event's, shift's or leg's uid, and a pose batch carrying
another vehicle's pose uid, are refused with 409 and change nothing; the owner's
own retry answers 200 with the row stored first."""

import uuid

import pytest

from events.models import Note, SegmentType
from events.services import logs, notes, segments
from telemetry.models import LocalPose, Pose
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db


@pytest.fixture
def two_segments(leg, other_leg):
    return (
        segments.report_mode(leg, SegmentType.AUTO).master,
        segments.report_mode(other_leg, SegmentType.AUTO).master,
    )


def _note_case(test_event, shift, leg, other_leg, two_segments):
    ours, theirs = two_segments
    first = notes.add_note(theirs, text="the other segment's note", uid=uuid.uuid4())
    own = {"segment": theirs.pk, "text": "sent again"}
    return "/api/notes/", first, {"segment": ours.pk, "text": "mine"}, own


def _test_event_case(test_event, shift, leg, other_leg, two_segments):
    first = logs.create_test_event(location="Wachtberg", uid=uuid.uuid4())
    return "/api/test-events/", first, {"location": "Bonn"}, {"location": "Wachtberg"}


def _shift_case(test_event, shift, leg, other_leg, two_segments):
    # The other vehicle's shift; the request names our vehicle.
    first = other_leg.shift
    return (
        "/api/shifts/",
        first,
        {"test_event": test_event.pk, "vehicle": shift.vehicle_id},
        {"test_event": test_event.pk, "vehicle": first.vehicle_id},
    )


def _leg_case(test_event, shift, leg, other_leg, two_segments):
    first = other_leg
    return "/api/legs/", first, {"shift": shift.pk}, {"shift": first.shift_id}


CASES = {
    "note": _note_case,
    "test event": _test_event_case,
    "shift": _shift_case,
    "leg": _leg_case,
}


@pytest.mark.parametrize("kind", CASES)
def test_another_rows_uid_is_refused_and_changes_nothing(
    kind, api_client, test_event, shift, leg, other_leg, two_segments
):
    url, first, body, own = CASES[kind](test_event, shift, leg, other_leg, two_segments)
    client = api_client("operator")
    before = snapshot()

    answer = client.post(url, {**body, "uid": str(first.uid)}, format="json")

    assert answer.status_code == 409, answer.content
    assert "uid" in answer.json()["errors"]
    assert "id" not in answer.json()
    assert snapshot() == before
    # The owner's own retry is answered with the row stored first.
    again = client.post(url, {**own, "uid": str(first.uid)}, format="json")
    assert again.status_code == 200, again.content
    assert again.json()["id"] == first.pk
    assert snapshot() == before


def test_a_note_sent_from_the_cockpit_with_another_notes_uid_is_refused(
    client, role_user, two_segments
):
    """The cockpit posts notes with the signed-in session, as segment-dialog.js does."""
    ours, theirs = two_segments
    first = notes.add_note(theirs, text="theirs", uid=uuid.uuid4())
    client.force_login(role_user("operator"))

    answer = client.post(
        "/api/notes/",
        {"uid": str(first.uid), "segment": ours.pk, "text": "mine"},
        content_type="application/json",
    )

    assert answer.status_code == 409, answer.content
    assert list(Note.objects.values_list("segment_id", "text")) == [(theirs.pk, "theirs")]


BATCHES = {
    "poses": (
        "/api/poses/batch/",
        Pose,
        lambda uid, x: {"uid": uid, "longitude": 7.0 + x / 1e4, "latitude": 50.6},
    ),
    "local poses": (
        "/api/local-poses/batch/",
        LocalPose,
        lambda uid, x: {"uid": uid, "frame": "map", "x": float(x), "y": 1.0},
    ),
}


@pytest.mark.parametrize("kind", BATCHES)
def test_a_batch_with_another_vehicles_uid_stores_none_of_its_poses(
    kind, robot_client, vehicle, other_vehicle, two_segments
):
    url, model, pose = BATCHES[kind]
    ours, theirs = two_segments
    taken = str(uuid.uuid4())
    stored = robot_client(other_vehicle).post(
        url, {"segment": theirs.pk, "poses": [pose(taken, 0)]}, format="json"
    )
    assert stored.status_code == 201, stored.content
    batch = [pose(str(uuid.uuid4()), 1), pose(taken, 2), pose(str(uuid.uuid4()), 3)]

    answer = robot_client(vehicle).post(url, {"segment": ours.pk, "poses": batch}, format="json")

    assert answer.status_code == 409, answer.content
    assert "uid" in answer.json()["errors"]
    assert not model.objects.filter(segment=ours).exists()
    assert model.objects.filter(segment=theirs).count() == 1
    # Its own batch sent again stores nothing twice and is no conflict.
    again = robot_client(other_vehicle).post(
        url, {"segment": theirs.pk, "poses": [pose(taken, 0)]}, format="json"
    )
    assert again.status_code == 201 and again.json()["stored"] == 0
