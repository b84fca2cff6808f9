"""A uid sent again is a retry only for the same owner (issue 31, finding 8): a
robot that sends another vehicle's uid for its own segment or shift gets 409
and never the other vehicle's row."""

import uuid

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile

from events.models import SegmentType
from events.services import segments
from telemetry.models import Image, LocalPose, MapImage, Pose
from tests.support.images import map_form, png


def _image(segment, uid):
    upload = SimpleUploadedFile("frame.png", png(), content_type="image/png")
    return {"segment": segment.pk, "uid": uid, "image": upload}


CASES = {
    "pose": (
        "/api/poses/",
        Pose,
        "json",
        lambda m, uid: {"segment": m.pk, "uid": uid, "longitude": 8.25, "latitude": 50.5},
    ),
    "local pose": (
        "/api/local-poses/",
        LocalPose,
        "json",
        lambda m, uid: {"segment": m.pk, "uid": uid, "frame": "map", "x": 12.5, "y": -3.0},
    ),
    "image": ("/api/images/", Image, "multipart", _image),
    "map": ("/api/maps/", MapImage, "multipart", lambda m, uid: map_form(m.leg.shift, uid=uid)),
}


@pytest.mark.parametrize("kind", CASES)
def test_another_vehicles_uid_is_refused_without_its_row(
    kind, robot_client, vehicle, other_vehicle, leg, other_leg, media_root
):
    url, model, fmt, body = CASES[kind]
    uid = str(uuid.uuid4())
    theirs = segments.report_mode(other_leg, SegmentType.AUTO).master
    ours = segments.report_mode(leg, SegmentType.AUTO).master
    first = robot_client(other_vehicle).post(url, body(theirs, uid), format=fmt)
    assert first.status_code == 201, first.content
    client = robot_client(vehicle)

    answer = client.post(url, body(ours, uid), format=fmt)

    assert answer.status_code in (403, 409), answer.content
    assert "uid" in answer.json()["errors"]
    assert str(first.json()["id"]) not in answer.content.decode()
    assert model.objects.filter(uid=uid).count() == 1
    # Its own retry is answered with the row stored first.
    again = robot_client(other_vehicle).post(url, body(theirs, uid), format=fmt)
    assert again.status_code == 200 and again.json()["id"] == first.json()["id"]


def test_another_vehicles_segment_uid_sent_to_mode_is_refused_without_its_row(
    robot_client, vehicle, other_vehicle, leg, other_leg
):
    uid = str(uuid.uuid4())
    first = robot_client(other_vehicle).post(
        f"/api/legs/{other_leg.pk}/mode/", {"mode": "auto", "uid": uid}, format="json"
    )
    assert first.status_code in (200, 201), first.content
    theirs = first.json()

    answer = robot_client(vehicle).post(
        f"/api/legs/{leg.pk}/mode/", {"mode": "auto", "uid": uid}, format="json"
    )

    assert answer.status_code == 409, answer.content
    assert "uid" in answer.json()["errors"]
    assert str(other_leg.pk) not in str(answer.json().get("leg", ""))
    assert leg.segments.count() == 0
    again = robot_client(other_vehicle).post(
        f"/api/legs/{other_leg.pk}/mode/", {"mode": "auto", "uid": uid}, format="json"
    )
    assert again.status_code == 200
    assert {**again.json(), "changed": True} == {**theirs, "changed": True}
