"""A robot's token writes telemetry into its own vehicle's legs only."""

import uuid

import pytest

from common import roles
from events.models import RobotAccount
from telemetry.models import Image, LocalPose, MapImage, Pose
from tests.support.api import assert_error_shape
from tests.support.images import upload
from tests.support.modes import start_auto


@pytest.fixture
def other_master(other_leg):
    return start_auto(other_leg)


def _pose(segment):
    return {"segment": segment.pk, "longitude": 7.1, "latitude": 50.2, "uid": str(uuid.uuid4())}


def _pose_batch(segment):
    return {"segment": segment.pk, "poses": [{"longitude": 7.0, "latitude": 50.0}]}


def _local_pose(segment):
    return {"segment": segment.pk, "frame": "map", "x": 1.0, "y": 2.0}


def _local_batch(segment):
    return {"segment": segment.pk, "poses": [{"frame": "map", "x": 1.0, "y": 2.0}]}


JSON_WRITES = {
    "/api/poses/": (_pose, Pose),
    "/api/poses/batch/": (_pose_batch, Pose),
    "/api/local-poses/": (_local_pose, LocalPose),
    "/api/local-poses/batch/": (_local_batch, LocalPose),
}


@pytest.mark.parametrize("url", JSON_WRITES)
def test_a_robot_writes_poses_into_its_vehicles_leg(url, robot_client, vehicle, auto_master):
    body, model = JSON_WRITES[url]
    response = robot_client(vehicle).post(url, body(auto_master), format="json")
    assert response.status_code == 201, response.content
    assert model.objects.filter(segment=auto_master).count() == 1


@pytest.mark.parametrize("url", JSON_WRITES)
def test_a_robot_is_refused_poses_into_another_vehicles_leg(
    url, robot_client, vehicle, auto_master, other_master
):
    body, model = JSON_WRITES[url]
    response = robot_client(vehicle).post(url, body(other_master), format="json")
    detail = assert_error_shape(response, 403)["detail"]
    assert "vehicle husky" in detail and "vehicle jackal" in detail
    assert not model.objects.exists()


def _map(shift):
    return {
        "shift": shift.pk,
        "frame": "map",
        "width": 4,
        "height": 3,
        "resolution": 0.1,
        "origin_x": 0.0,
        "origin_y": 0.0,
        "image": upload(colour=(1, 2, 3)),
    }


def _image(segment):
    return {"segment": segment.pk, "image": upload("frame.jpg", fmt="JPEG")}


def test_a_robot_uploads_maps_and_images_for_its_vehicle_only(
    robot_client, vehicle, auto_master, other_master, media_root
):
    robot = robot_client(vehicle)
    for url, own, other, model in (
        ("/api/maps/", _map(auto_master.leg.shift), _map(other_master.leg.shift), MapImage),
        ("/api/images/", _image(auto_master), _image(other_master), Image),
    ):
        refused = robot.post(url, other, format="multipart")
        assert "vehicle jackal" in assert_error_shape(refused, 403)["detail"], url
        assert not model.objects.exists()
        stored = robot.post(url, own, format="multipart")
        assert stored.status_code == 201, stored.content
        assert model.objects.count() == 1


def test_a_robot_neither_reads_nor_deletes_telemetry(robot_client, vehicle, auto_master):
    robot = robot_client(vehicle)
    pose = robot.post("/api/poses/", _pose(auto_master), format="json").json()
    for method, url in (
        ("get", "/api/poses/"),
        ("get", f"/api/poses/{pose['id']}/"),
        ("delete", f"/api/poses/{pose['id']}/"),
        ("get", "/api/recordings/"),
        ("get", f"/api/maps/current/?shift={auto_master.leg.shift_id}"),
    ):
        assert_error_shape(getattr(robot, method)(url), 403)
    assert Pose.objects.filter(pk=pose["id"]).exists()


def test_operators_write_telemetry_into_every_vehicles_leg(
    api_client, robot_client, vehicle, auto_master, other_master
):
    robot_client(vehicle)
    operator = api_client(roles.OPERATOR)
    for master in (auto_master, other_master):
        response = operator.post("/api/poses/", _pose(master), format="json")
        assert response.status_code == 201, response.content
    assert Pose.objects.count() == 2


def test_a_robot_unbound_from_its_vehicle_is_refused_at_once(robot_client, vehicle, leg):
    """Its vehicles are kept between requests, but not past a change of its binding."""
    client = robot_client(vehicle)
    master = start_auto(leg)
    assert client.post("/api/poses/", _pose(master), format="json").status_code == 201
    RobotAccount.objects.get(user=client.user).vehicles.remove(vehicle)
    response = client.post("/api/poses/", _pose(master), format="json")
    assert_error_shape(response, 403)
    assert Pose.objects.filter(segment=master).count() == 1
