"""The rule actions (close, re-open, mode, manual segment, ITO children, annotation) over HTTP."""

import uuid

import pytest

from common import roles
from events.models import Segment, SegmentType, Shift
from events.models import TestEvent as TestEventModel
from events.services import finality, logs, segments
from tests.support.api import assert_error_shape
from tests.support.modes import start_auto


@pytest.fixture
def operator(api_client):
    return api_client(roles.OPERATOR)


def mode(client, leg, value, **extra):
    return client.post(f"/api/legs/{leg.pk}/mode/", {"mode": value, **extra}, format="json")


# --- closing and re-opening -------------------------------------------------------------


def test_closing_a_test_event_closes_everything_below(operator, leg):
    segments.report_mode(leg, SegmentType.AUTO)
    event = leg.shift.test_event
    response = operator.post(f"/api/test-events/{event.pk}/close/")
    assert response.status_code == 200, response.content
    assert response.json()["is_open"] is False
    assert not Segment.objects.filter(end__isnull=True).exists()
    assert not Shift.objects.filter(end__isnull=True).exists()

    again = assert_error_shape(operator.post(f"/api/test-events/{event.pk}/close/"), 409)
    assert "closed" in again["detail"]


def test_reopening_a_test_event_keeps_its_shifts_closed(operator, shift):
    event = shift.test_event
    logs.close_test_event(event)
    response = operator.post(f"/api/test-events/{event.pk}/reopen/")
    assert response.status_code == 200
    assert response.json()["end"] is None
    shift.refresh_from_db()
    assert shift.end is not None
    assert_error_shape(operator.post(f"/api/test-events/{event.pk}/reopen/"), 409)


def test_a_row_says_whether_it_may_reopen_as_the_reopen_action_answers(operator, leg):
    """The cockpit shows Re-open from the row's may_reopen: only a closed test event, not final."""
    event = leg.shift.test_event

    def row(path, pk):
        return operator.get(f"/api/{path}/{pk}/").json()["may_reopen"]

    assert row("test-events", event.pk) is False  # open
    logs.close_test_event(event)
    assert row("shifts", leg.shift_id) is False and row("legs", leg.pk) is False
    assert (
        operator.get("/api/shifts/", {"test_event": event.pk}).json()["results"][0]["may_reopen"]
        is False
    )
    assert row("test-events", event.pk) is True
    finality.finalise_test_event(TestEventModel.objects.get(pk=event.pk))
    assert row("test-events", event.pk) is False
    assert_error_shape(operator.post(f"/api/test-events/{event.pk}/reopen/"), 409)


def test_closing_a_shift_and_a_leg(operator, leg):
    response = operator.post(f"/api/legs/{leg.pk}/close/")
    assert response.status_code == 200 and response.json()["is_open"] is False
    assert_error_shape(operator.post(f"/api/legs/{leg.pk}/close/"), 409)
    response = operator.post(f"/api/shifts/{leg.shift_id}/close/")
    assert response.status_code == 200 and response.json()["end"] is not None


def test_viewer_cannot_run_actions(api_client, leg):
    viewer = api_client(roles.VIEWER)
    assert_error_shape(viewer.post(f"/api/legs/{leg.pk}/close/"), 403)
    assert_error_shape(mode(viewer, leg, "auto"), 403)
    leg.refresh_from_db()
    assert leg.is_open and not leg.segments.exists()


def test_viewer_is_refused_every_rule_action_and_nothing_changes(api_client, leg):
    master = segments.report_mode(leg, SegmentType.ITO).master
    child = master.children.get()
    event, shift = leg.shift.test_event, leg.shift
    viewer = api_client(roles.VIEWER)
    attempts = [
        (f"/api/test-events/{event.pk}/close/", {}),
        (f"/api/test-events/{event.pk}/reopen/", {}),
        (f"/api/shifts/{shift.pk}/close/", {}),
        (f"/api/legs/{leg.pk}/manual-segment/", {"ito_reason": "safety"}),
        (f"/api/segments/{master.pk}/children/", {"ito_reason": "planner"}),
        (f"/api/segments/{child.pk}/close/", {}),
    ]
    for url, body in attempts:
        assert_error_shape(viewer.post(url, body, format="json"), 403)
    patched = viewer.patch(f"/api/segments/{child.pk}/", {"obstacle": "x"}, format="json")
    assert_error_shape(patched, 403)
    assert Segment.objects.filter(leg=leg).count() == 2
    assert not Segment.objects.filter(leg=leg, end__isnull=False).exists()
    child.refresh_from_db()
    assert child.obstacle == "" and child.ito_reason_id == "unassigned"
    assert TestEventModel.objects.get(pk=event.pk).end is None
    assert Shift.objects.get(pk=shift.pk).end is None


# --- the mode endpoint the collector uses ----------------------------------------------


def test_mode_change_opens_a_master_and_repeating_it_changes_nothing(operator, leg):
    first = mode(operator, leg, "auto", longitude=0.0, latitude=0.0, local_x=0.0, local_y=0.0)
    assert first.status_code == 201, first.content
    body = first.json()
    assert body["changed"] is True
    assert body["segment"]["segment_type"] == "auto"
    # 0.0 is a real position, not "missing".
    assert body["segment"]["start_position"]["coordinates"] == [0.0, 0.0]
    assert body["segment"]["start_local_x"] == 0.0

    repeat = mode(operator, leg, "auto")
    assert repeat.status_code == 200
    assert repeat.json() == {**body, "changed": False}
    assert leg.segments.count() == 1


def test_switch_to_ito_closes_auto_and_opens_master_with_unassigned_child(operator, leg):
    auto = mode(operator, leg, "auto").json()["segment"]
    stamp = "2026-05-04T10:00:00.250000+02:00"
    ito = mode(operator, leg, "ito", robot_stamp=stamp, local_frame="map", local_x=1, local_y=2)
    assert ito.status_code == 201
    master = Segment.objects.get(pk=ito.json()["segment"]["id"])
    assert master.robot_stamp.isoformat() == "2026-05-04T08:00:00.250000+00:00"
    assert master.start_local_frame == "map"
    assert [c.ito_reason_id for c in master.children.all()] == ["unassigned"]
    assert Segment.objects.get(pk=auto["id"]).end == master.start


def test_mode_with_a_known_uid_is_a_no_op(operator, leg):
    uid = str(uuid.uuid4())
    first = mode(operator, leg, "ito", uid=uid)
    mode(operator, leg, "auto")
    retry = mode(operator, leg, "ito", uid=uid)
    assert retry.status_code == 200
    assert retry.json()["segment"]["id"] == first.json()["segment"]["id"]
    assert leg.segments.filter(parent__isnull=True).count() == 2


@pytest.mark.parametrize(
    "payload, field",
    [
        ({"mode": "manual"}, "mode"),
        ({}, "mode"),
        ({"mode": "auto", "longitude": 7.1}, "latitude"),
        ({"mode": "auto", "latitude": 91, "longitude": 7}, "latitude"),
        ({"mode": "auto", "local_y": 3}, "local_x"),
        ({"mode": "auto", "robot_stamp": "yesterday"}, "robot_stamp"),
        ({"mode": "ito", "reason": "bored"}, "reason"),
        ({"mode": "auto", "uid": "not-a-uuid"}, "uid"),
    ],
)
def test_bad_mode_reports_are_400_with_the_field(operator, leg, payload, field):
    response = operator.post(f"/api/legs/{leg.pk}/mode/", payload, format="json")
    body = assert_error_shape(response, 400)
    assert field in body["errors"]
    assert not leg.segments.exists()


def test_mode_on_a_closed_leg_is_409(operator, leg):
    logs.close_leg(leg)
    body = assert_error_shape(mode(operator, leg, "auto"), 409)
    assert "Leg 1" in body["detail"]


# --- operator segments and annotation --------------------------------------------------


def test_manual_segment_while_auto_switches_to_ito(operator, leg):
    segments.report_mode(leg, SegmentType.AUTO)
    response = operator.post(
        f"/api/legs/{leg.pk}/manual-segment/", {"reason": "safety"}, format="json"
    )
    assert response.status_code == 201, response.content
    child = response.json()
    assert child["ito_reason"] == "safety" and child["is_master"] is False
    master = Segment.objects.get(pk=child["parent"])
    assert master.segment_type_id == SegmentType.ITO and master.is_open
    assert not leg.segments.filter(segment_type=SegmentType.AUTO, end__isnull=True).exists()


def test_children_add_a_second_reason_and_refuse_auto(operator, leg):
    ito = segments.report_mode(leg, SegmentType.ITO).master
    response = operator.post(
        f"/api/segments/{ito.pk}/children/", {"reason": "maintenance"}, format="json"
    )
    assert response.status_code == 201
    assert sorted(ito.children.values_list("ito_reason", flat=True)) == [
        "maintenance",
        "unassigned",
    ]
    auto = start_auto(leg)
    body = assert_error_shape(operator.post(f"/api/segments/{auto.pk}/children/"), 409)
    assert "AUTO" in body["detail"]


def test_closing_a_child_leaves_the_master_open(operator, leg):
    master = segments.report_mode(leg, SegmentType.ITO).master
    child = master.children.get()
    response = operator.post(f"/api/segments/{child.pk}/close/")
    assert response.status_code == 200 and response.json()["is_open"] is False
    master.refresh_from_db()
    assert master.is_open
    response = operator.post(f"/api/segments/{master.pk}/close/")
    assert response.status_code == 200
    assert_error_shape(operator.post(f"/api/segments/{master.pk}/close/"), 409)


def test_annotating_a_reason_and_refusing_auto(operator, leg):
    master = segments.report_mode(leg, SegmentType.ITO).master
    child = master.children.get()
    response = operator.patch(
        f"/api/segments/{child.pk}/",
        {"ito_reason": "safety", "obstacle": "fence", "lighting": "", "slope": "steep"},
        format="json",
    )
    assert response.status_code == 200, response.content
    child.refresh_from_db()
    assert (child.ito_reason_id, child.obstacle, child.slope) == ("safety", "fence", "steep")

    auto = start_auto(leg)
    body = assert_error_shape(
        operator.patch(f"/api/segments/{auto.pk}/", {"obstacle": "x"}, format="json"), 409
    )
    assert "AUTO" in body["detail"]
    body = assert_error_shape(
        operator.patch(f"/api/segments/{child.pk}/", {"ito_reason": "nope"}, format="json"), 400
    )
    assert "ito_reason" in body["errors"]


def test_segments_cannot_be_posted_directly(operator, leg):
    assert_error_shape(operator.post("/api/segments/", {"leg": leg.pk}, format="json"), 405)


# --- the collector's look-up ------------------------------------------------------------


def test_current_leg_of_a_vehicle_by_key_and_id(api_client, leg, vehicle):
    viewer = api_client(roles.VIEWER)
    response = viewer.get(f"/api/vehicles/{vehicle.key}/current-leg/")
    assert response.status_code == 200
    assert response.json()["id"] == leg.pk and response.json()["open_segment"] is None
    master = start_auto(leg)
    by_id = viewer.get(f"/api/vehicles/{vehicle.pk}/current-leg/").json()
    assert by_id["open_segment"]["id"] == master.pk
    logs.close_leg(leg)
    assert_error_shape(viewer.get(f"/api/vehicles/{vehicle.key}/current-leg/"), 404)


# --- idempotent creation ----------------------------------------------------------------


def test_create_with_a_known_uid_returns_the_first_row(operator, db):
    uid = str(uuid.uuid4())
    first = operator.post("/api/test-events/", {"uid": uid, "location": "A"}, format="json")
    assert first.status_code == 201
    retry = operator.post("/api/test-events/", {"uid": uid, "location": "A"}, format="json")
    assert retry.status_code == 200
    assert retry.json() == first.json()
    assert TestEventModel.objects.count() == 1


def test_leg_and_note_retries_create_one_row(operator, shift):
    uid = str(uuid.uuid4())
    codes = [
        operator.post("/api/legs/", {"uid": uid, "shift": shift.pk}, format="json").status_code
        for _ in range(2)
    ]
    assert codes == [201, 200] and shift.legs.count() == 1
    leg = shift.legs.get()
    segment = segments.new_manual_segment(leg)
    note_uid = str(uuid.uuid4())
    payload = {"uid": note_uid, "segment": segment.pk, "text": "again"}
    codes = [operator.post("/api/notes/", payload, format="json").status_code for _ in range(2)]
    assert codes == [201, 200] and segment.notes.count() == 1
