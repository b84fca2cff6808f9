"""A robot's token logs into legs of its own vehicles and nothing else; operators keep
their rights over every vehicle."""

import pytest
from django.contrib.auth.models import Group

from common import roles
from events.models import Note, Segment, SegmentType, TestEvent
from events.services import logs, segments
from tests.support.api import assert_error_shape
from tests.support.modes import start_auto


def _mode(client, leg, mode="auto"):
    return client.post(f"/api/legs/{leg.pk}/mode/", {"mode": mode}, format="json")


def test_a_robot_reports_modes_into_its_vehicles_leg(robot_client, vehicle, leg):
    robot = robot_client(vehicle)
    response = _mode(robot, leg)
    assert response.status_code == 201, response.content
    assert response.json()["segment"]["segment_type"] == SegmentType.AUTO
    assert _mode(robot, leg, "ito").status_code == 201
    master = Segment.objects.get(leg=leg, parent__isnull=True, end__isnull=True)
    assert master.segment_type_id == SegmentType.ITO


def test_a_robot_is_refused_another_vehicles_leg_naming_both(robot_client, vehicle, leg, other_leg):
    body = assert_error_shape(_mode(robot_client(vehicle), other_leg), 403)
    assert "vehicle husky" in body["detail"] and "vehicle jackal" in body["detail"]
    assert not Segment.objects.filter(leg=other_leg).exists()


def test_a_robot_bound_to_two_vehicles_logs_for_both(robot_client, vehicle, other_vehicle, leg):
    other_leg = logs.create_leg(
        shift=logs.create_shift(test_event=leg.shift.test_event, vehicle=other_vehicle)
    )
    robot = robot_client(vehicle, other_vehicle)
    assert _mode(robot, leg).status_code == 201
    assert _mode(robot, other_leg).status_code == 201


def test_a_robot_bound_to_no_vehicle_logs_nothing(robot_client, leg):
    body = assert_error_shape(_mode(robot_client(), leg), 403)
    assert "bound to no vehicle" in body["detail"]
    assert not Segment.objects.filter(leg=leg).exists()


def test_a_robot_in_the_operator_group_too_stays_bound(robot_client, vehicle, leg, other_leg):
    robot = robot_client(vehicle)
    robot.user.groups.add(Group.objects.get(name=roles.OPERATOR))
    assert_error_shape(_mode(robot, other_leg), 403)
    assert_error_shape(robot.delete(f"/api/test-events/{leg.shift.test_event_id}/"), 403)
    assert _mode(robot, leg).status_code == 201


def test_a_robot_may_not_delete_a_test_event(robot_client, vehicle, leg):
    event = logs.create_test_event(location="Spare")
    robot = robot_client(vehicle)
    for url in (f"/api/test-events/{event.pk}/", f"/api/test-events/{leg.shift.test_event_id}/"):
        body = assert_error_shape(robot.delete(url), 403)
        assert "robot account" in body["detail"]
    assert TestEvent.objects.filter(pk__in=[event.pk, leg.shift.test_event_id]).count() == 2


def test_a_robot_may_do_nothing_but_log(robot_client, vehicle, leg):
    """Not even on its own vehicle: no notes, no closing, no new log levels, no lists."""
    master = segments.report_mode(leg, SegmentType.ITO).master
    child = master.children.get()
    robot = robot_client(vehicle)
    shift, event = leg.shift, leg.shift.test_event
    refused = [
        ("post", "/api/notes/", {"segment": child.pk, "text": "spoofed"}),
        ("post", f"/api/legs/{leg.pk}/close/", None),
        ("post", f"/api/shifts/{shift.pk}/close/", None),
        ("post", f"/api/test-events/{event.pk}/close/", None),
        ("post", "/api/legs/", {"shift": shift.pk}),
        ("post", f"/api/legs/{leg.pk}/manual-segment/", {}),
        ("post", f"/api/segments/{master.pk}/children/", {}),
        ("patch", f"/api/segments/{child.pk}/", {"obstacle": "tree"}),
        ("delete", f"/api/segments/{child.pk}/", None),
        ("patch", f"/api/vehicles/{vehicle.key}/", {"short_description": "x"}),
        ("get", "/api/legs/", None),
        ("get", "/api/notes/", None),
        ("get", "/api/test-events/", None),
        ("get", f"/api/test-events/{event.pk}/", None),
        ("get", "/api/vehicles/", None),
        ("get", "/api/personnel/", None),
        ("get", f"/api/tracks/?leg={leg.pk}", None),
    ]
    for method, url, body in refused:
        response = getattr(robot, method)(url, body, format="json")
        assert_error_shape(response, 403)
    assert not Note.objects.exists()
    leg.refresh_from_db()
    child.refresh_from_db()
    assert leg.is_open and child.is_open and child.obstacle == ""
    assert Segment.objects.filter(leg=leg).count() == 2


def test_a_robot_reads_where_it_logs(robot_client, vehicle, leg, pose_source):
    master = start_auto(leg)
    robot = robot_client(vehicle)
    current = robot.get(f"/api/vehicles/{vehicle.key}/current-leg/")
    assert current.status_code == 200, current.content
    assert current.json()["id"] == leg.pk
    assert current.json()["open_segment"]["id"] == master.pk
    for url in (
        f"/api/vehicles/{vehicle.key}/",
        f"/api/legs/{leg.pk}/",
        f"/api/shifts/{leg.shift_id}/",
        f"/api/segments/{master.pk}/",
        "/api/pose-sources/",
        f"/api/pose-sources/{pose_source.pk}/",
        "/api/ito-reasons/",
        "/api/segment-types/",
        "/api/weather/",
    ):
        assert robot.get(url).status_code == 200, url


def test_a_robot_reads_nothing_of_another_vehicle(robot_client, vehicle, other_leg):
    other_vehicle = other_leg.shift.vehicle
    master = start_auto(other_leg)
    robot = robot_client(vehicle)
    for url in (
        f"/api/vehicles/{other_vehicle.key}/current-leg/",
        f"/api/vehicles/{other_vehicle.pk}/",
        f"/api/legs/{other_leg.pk}/",
        f"/api/shifts/{other_leg.shift_id}/",
        f"/api/segments/{master.pk}/",
    ):
        body = assert_error_shape(robot.get(url), 403)
        assert "vehicle jackal" in body["detail"], url


@pytest.mark.parametrize("role", [roles.OPERATOR, roles.ADMINISTRATOR])
def test_operators_keep_their_rights_over_every_vehicle(
    api_client, robot_client, vehicle, leg, other_leg, role
):
    robot_client(vehicle)  # a robot account exists; people are not bound by it
    person = api_client(role)
    assert _mode(person, leg).status_code == 201
    assert _mode(person, other_leg).status_code == 201
    event = logs.create_test_event(location="Spare")
    assert person.delete(f"/api/test-events/{event.pk}/").status_code == 204
    assert not TestEvent.objects.filter(pk=event.pk).exists()
