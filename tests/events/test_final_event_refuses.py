"""What a final test event refuses (issue 46, items 1 and 3): poses, local poses,
maps, images, notes, judgements and segment edits are refused on every write
path, from operators, robots, the collector and archives, and nothing is
stored; an administrator's amendment with a reason is the only way in."""

import uuid
from datetime import UTC, datetime

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile

from events.history import authored
from events.models import Criterion, Judgement, Note, SegmentType, TestCase
from events.services import finality, logs, segments
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.event_writer import EventWriter, GivenMaster
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.services import pose_writes
from telemetry.services.segment_figures import recount_figures
from tests.support.images import map_form, png
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db

STAMP = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)


@pytest.fixture
def final(leg):
    """A closed and finalised test event: one AUTO master with a pose, a judged criterion."""
    master = segments.report_mode(leg, SegmentType.AUTO).master
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.1, 50.6, robot_stamp=STAMP)])
    event = leg.shift.test_event
    case = TestCase.objects.create(test_event=event, key="loop", title="Loop")
    criterion = Criterion.objects.create(
        test_case=case, kind=Criterion.Kind.JUDGED, text="Stays on the track"
    )
    logs.close_test_event(event)
    finality.finalise_test_event(event)
    master.refresh_from_db()
    return {"event": event, "master": master, "leg": leg, "criterion": criterion}


ROBOT_WRITES = {
    "pose": ("/api/poses/", "json", lambda f: {"segment": f["master"].pk, **_fix()}),
    "pose batch": (
        "/api/poses/batch/",
        "json",
        lambda f: {"segment": f["master"].pk, "poses": [_fix()]},
    ),
    "local pose": (
        "/api/local-poses/",
        "json",
        lambda f: {"segment": f["master"].pk, "frame": "map", "x": 1.0, "y": 2.0},
    ),
    "local pose batch": (
        "/api/local-poses/batch/",
        "json",
        lambda f: {"segment": f["master"].pk, "poses": [{"frame": "map", "x": 1.0, "y": 2.0}]},
    ),
    "map": ("/api/maps/", "multipart", lambda f: map_form(f["leg"].shift)),
    "image": (
        "/api/images/",
        "multipart",
        lambda f: {
            "segment": f["master"].pk,
            "image": SimpleUploadedFile("a.png", png(), content_type="image/png"),
        },
    ),
}


def _fix():
    return {"longitude": 7.2, "latitude": 50.7, "robot_stamp": "2026-05-04T10:00:05Z"}


@pytest.mark.parametrize("kind", ROBOT_WRITES)
def test_a_robot_sends_nothing_into_a_final_event(kind, final, robot_client, vehicle, media_root):
    url, fmt, body = ROBOT_WRITES[kind]
    before = snapshot()

    answer = robot_client(vehicle).post(url, body(final), format=fmt)

    assert answer.status_code == 403, answer.content
    assert "final" in answer.json()["detail"]
    assert snapshot() == before


def test_an_operator_judges_nothing_in_a_final_event(final, api_client):
    before = snapshot()
    body = {"criterion": final["criterion"].pk, "passed": True, "note": "fine"}

    answer = api_client("operator").post("/api/reports/judgements/", body, format="json")

    assert answer.status_code == 403, answer.content
    assert "final" in answer.json()["detail"]
    assert snapshot() == before


def test_the_cockpit_judges_and_notes_nothing_in_a_final_event(final, client, role_user):
    """The pages write with the signed-in session (testplan.js, segment-dialog.js)."""
    client.force_login(role_user("operator"))
    judged = client.post(
        "/api/reports/judgements/",
        {"criterion": final["criterion"].pk, "passed": True},
        content_type="application/json",
    )
    noted = client.post(
        "/api/notes/",
        {"segment": final["master"].pk, "text": "late"},
        content_type="application/json",
    )
    assert (judged.status_code, noted.status_code) == (403, 403)
    assert not Judgement.objects.exists() and not Note.objects.exists()


def test_an_administrator_amends_a_final_event_only_with_a_reason(final, api_client):
    admin = api_client("administrator")
    body = {"criterion": final["criterion"].pk, "passed": True}
    refused = admin.post("/api/reports/judgements/", body, format="json")
    assert refused.status_code == 400 and "reason" in refused.json()["errors"]
    with authored(user=admin.user, reason="verdict from the written protocol"):
        pose_writes.store_poses(final["master"], [pose_writes.GpsFix(7.3, 50.8, robot_stamp=STAMP)])
    assert Pose.objects.filter(segment=final["master"]).count() == 2


def test_the_admin_adds_no_judgement_to_a_final_event_without_a_reason(
    final, client, django_user_model
):
    client.force_login(django_user_model.objects.create_superuser("root", password="pw"))
    body = {"criterion": final["criterion"].pk, "passed": "on"}

    judged = client.post("/admin/events/judgement/add/", body)

    assert judged.status_code == 200  # the form again, with its error
    assert "amendment needs a reason" in judged.content.decode()
    assert not Judgement.objects.exists()
    amended = client.post("/admin/events/judgement/add/", {**body, "change_reason": "protocol"})
    assert amended.status_code == 302 and Judgement.objects.count() == 1


def test_the_collector_stores_nothing_into_a_final_event(final, media_root):
    """The collector's writer (the EventWriter the live collector's writer loop
    applies its spool with), given a master of a final event by a late backlog."""
    before = snapshot()
    events = [
        ev.Event(ev.GPS_FIX, STAMP, {"lon": 7.2, "lat": 50.7}, uid=uuid.uuid4()),
        ev.Event(ev.LOCAL_POSE, STAMP, {"x": 1.0, "y": 2.0, "frame": "map"}, uid=uuid.uuid4()),
    ]
    event_writer = EventWriter(lambda: None)

    event_writer.apply(events, GivenMaster(str(final["master"].uid)))

    assert event_writer.skipped == 2
    assert snapshot() == before
    assert not LocalPose.objects.exists() and Pose.objects.count() == 1
    assert not Image.objects.exists() and not MapImage.objects.exists()


def test_a_single_pose_amends_a_final_event_only_with_an_administrators_reason(final, api_client):
    """The single pose's insert refuses a final event itself (docs/ingest.md);
    the amendment then stores it, with its figures."""
    master, admin = final["master"], api_client("administrator")
    body = {"segment": master.pk, **_fix()}
    refused = admin.post("/api/poses/", body, format="json")
    assert refused.status_code == 400 and "reason" in refused.json()["errors"]
    assert Pose.objects.filter(segment=master).count() == 1
    with authored(user=admin.user, reason="a fix the spool kept"):
        pose_writes.store_pose(master.pk, pose_writes.GpsFix(7.3, 50.8, robot_stamp=STAMP))
    assert Pose.objects.filter(segment=master).count() == 2
    assert recount_figures([master.pk]) == {}
