"""The generic CRUD suite applied to the robot-data endpoints (no edits: robot data is
created and deleted, never changed)."""

import uuid

import pytest
from django.core.exceptions import ValidationError

from common import roles
from telemetry.models import LocalPose, MapImage, Pose
from telemetry.pictures import MAP_FORMATS, checked_picture
from telemetry.services import attachments, map_images, pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from tests.support.api import CrudTests, assert_error_shape
from tests.support.images import png, upload

RECORDED = ("create", "delete")


class TestPoses(CrudTests):
    basename = "pose"
    operations = RECORDED

    @pytest.fixture
    def instance(self, auto_master):
        fix = GpsFix(longitude=7.1, latitude=50.7)
        pose_writes.store_poses(auto_master, [fix])
        return Pose.objects.get(uid=fix.uid)

    @pytest.fixture
    def create_data(self, auto_master, pose_source):
        return {
            "segment": auto_master.pk,
            "longitude": 0.0,
            "latitude": 0.0,
            "altitude": 112.5,
            "fix_status": 2,
            "horizontal_accuracy": 0.02,
            "robot_stamp": "2026-05-04T10:00:00.123456Z",
            "pose_source": pose_source.pk,
        }

    @pytest.fixture
    def update_data(self):
        return {}

    def test_stored_as_sent(self, api_client, create_data):
        response = api_client(roles.OPERATOR).post(self.list_url(), create_data, format="json")
        pose = Pose.objects.get(pk=response.json()["id"])
        assert (pose.point.x, pose.point.y) == (0.0, 0.0)
        assert pose.robot_stamp.microsecond == 123456 and pose.fix_status == 2
        assert response.json()["longitude"] == 0.0

    def test_a_pose_for_a_reason_is_stored_on_its_master(self, api_client, leg):
        from events.services import segments

        child = segments.new_manual_segment(leg)
        response = api_client(roles.OPERATOR).post(
            self.list_url(), {"segment": child.pk, "longitude": 1, "latitude": 2}, format="json"
        )
        assert response.status_code == 201
        assert response.json()["segment"] == child.parent_id

    def test_retry_with_uid_and_batch(self, api_client, auto_master):
        client = api_client(roles.OPERATOR)
        uid = str(uuid.uuid4())
        body = {"segment": auto_master.pk, "longitude": 1, "latitude": 2, "uid": uid}
        codes = [client.post(self.list_url(), body, format="json").status_code for _ in "ab"]
        assert codes == [201, 200]
        batch = {
            "segment": auto_master.pk,
            "poses": [
                {"uid": uid, "longitude": 1, "latitude": 2},
                {"longitude": 3, "latitude": 4, "robot_stamp": "2026-05-04T10:00:01Z"},
            ],
        }
        response = client.post("/api/poses/batch/", batch, format="json")
        assert response.status_code == 201 and response.json() == {"stored": 1}
        assert auto_master.poses.count() == 2

    def test_batch_with_a_repeated_uid_is_refused(self, api_client, auto_master):
        uid = str(uuid.uuid4())
        pose = {"uid": uid, "longitude": 1, "latitude": 2}
        batch = {"segment": auto_master.pk, "poses": [pose, {**pose, "longitude": 3}]}
        response = api_client(roles.OPERATOR).post("/api/poses/batch/", batch, format="json")
        assert "poses" in assert_error_shape(response, 400)["errors"]
        assert not auto_master.poses.exists()

    def test_bad_batch_names_the_item(self, api_client, auto_master):
        batch = {"segment": auto_master.pk, "poses": [{"longitude": 1, "latitude": 200}]}
        body = assert_error_shape(
            api_client(roles.OPERATOR).post("/api/poses/batch/", batch, format="json"), 400
        )
        assert body["errors"]["poses"]["0"]["latitude"]
        assert body["detail"] == "Ensure this value is less than or equal to 90."
        assert not auto_master.poses.exists()

    def test_bounding_box_and_time_filters(self, api_client, auto_master):
        pose_writes.store_poses(
            auto_master,
            [
                GpsFix(7.0, 50.0, robot_stamp=_at(1)),
                GpsFix(8.0, 51.0, robot_stamp=_at(2)),
                GpsFix(-3.0, 40.0, robot_stamp=_at(3)),
            ],
        )
        client = api_client(roles.VIEWER)

        def longitudes(**query):
            response = client.get(self.list_url(), query)
            assert response.status_code == 200, response.content
            return sorted(p["longitude"] for p in response.json()["results"])

        assert longitudes(in_bbox="6.5,49.5,8.5,51.5") == [7.0, 8.0]
        assert longitudes(robot_stamp_after=_at(2).isoformat()) == [-3.0, 8.0]
        assert longitudes(robot_stamp_before=_at(2).isoformat()) == [7.0]
        assert longitudes(leg=auto_master.leg_id, page_size=2) == [7.0, 8.0]
        for bad in ("1,2,3", "a,b,c,d", "nan,0,1,1", "0,0,1,100"):
            body = assert_error_shape(client.get(f"{self.list_url()}?in_bbox={bad}"), 400)
            assert "in_bbox" in body["errors"]


def _at(second):
    from datetime import UTC, datetime

    return datetime(2026, 5, 4, 10, 0, second, tzinfo=UTC)


class TestLocalPoses(CrudTests):
    basename = "local-pose"
    operations = RECORDED

    @pytest.fixture
    def instance(self, auto_master):
        pose = MapPose(x=1.0, y=2.0, frame="map")
        pose_writes.store_local_poses(auto_master, [pose])
        return LocalPose.objects.get(uid=pose.uid)

    @pytest.fixture
    def create_data(self, auto_master):
        return {"segment": auto_master.pk, "frame": "map", "x": 0.0, "y": -4.5, "yaw": 3.1}

    @pytest.fixture
    def update_data(self):
        return {}

    def test_batch(self, api_client, auto_master):
        batch = {
            "segment": auto_master.pk,
            "poses": [{"frame": "map", "x": i, "y": -i} for i in range(5)],
        }
        response = api_client(roles.OPERATOR).post("/api/local-poses/batch/", batch, format="json")
        assert response.json() == {"stored": 5}
        assert sorted(auto_master.local_poses.values_list("x", flat=True)) == [0, 1, 2, 3, 4]


class TestMaps(CrudTests):
    basename = "map"
    operations = RECORDED
    format = "multipart"

    @pytest.fixture
    def instance(self, shift, media_root):
        map_image, _ = map_images.store_map(
            shift,
            png=png(),
            frame="map",
            width=4,
            height=3,
            resolution=0.05,
            origin_x=0.0,
            origin_y=0.0,
        )
        return map_image

    @pytest.fixture
    def create_data(self, shift, media_root):
        return {
            "shift": shift.pk,
            "frame": "map",
            "width": 4,
            "height": 3,
            "resolution": 0.1,
            "origin_x": -10.0,
            "origin_y": 0.0,
            "image": upload(colour=(1, 2, 3)),
        }

    @pytest.fixture
    def update_data(self):
        return {}

    def test_current_map_and_unchanged_upload(self, api_client, shift, create_data, instance):
        client = api_client(roles.OPERATOR)
        created = client.post(self.list_url(), create_data, format="multipart")
        assert created.status_code == 201
        assert created.json()["image"].startswith("http://testserver/media/maps/")
        current = client.get(f"/api/maps/current/?shift={shift.pk}")
        assert current.status_code == 200 and current.json()["id"] == created.json()["id"]
        # The same map again is not stored twice.
        again = client.post(
            self.list_url(), {**create_data, "image": upload(colour=(1, 2, 3))}, format="multipart"
        )
        assert again.status_code == 200 and again.json()["id"] == created.json()["id"]
        assert MapImage.objects.filter(shift=shift).count() == 2

    def test_current_map_errors(self, api_client, shift):
        client = api_client(roles.VIEWER)
        assert_error_shape(client.get(f"/api/maps/current/?shift={shift.pk}"), 404)
        assert_error_shape(client.get("/api/maps/current/"), 400)
        assert_error_shape(client.get("/api/maps/current/?shift=abc"), 400)

    def test_not_a_png_is_refused_in_the_words_of_the_map_rule(self, api_client, create_data):
        create_data["image"] = upload(name="map.jpg", fmt="JPEG")
        response = api_client(roles.OPERATOR).post(self.list_url(), create_data, format="multipart")
        # The API refuses with the rule every map write checks (telemetry.pictures), no copy.
        with pytest.raises(ValidationError) as rule:
            checked_picture(png(fmt="JPEG"), MAP_FORMATS)
        assert assert_error_shape(response, 400)["errors"]["image"] == ["Not a readable PNG image."]
        assert rule.value.message_dict["image"] == ["Not a readable PNG image."]
        assert not MapImage.objects.exists()


class TestImages(CrudTests):
    basename = "image"
    operations = RECORDED
    format = "multipart"

    @pytest.fixture
    def instance(self, auto_master, media_root):
        return attachments.attach_image(auto_master, content=png(fmt="JPEG"))

    @pytest.fixture
    def create_data(self, auto_master, media_root):
        return {
            "segment": auto_master.pk,
            "description": "front camera",
            "image": upload(name="front.jpg", fmt="JPEG"),
            "uid": str(uuid.uuid4()),
        }

    @pytest.fixture
    def update_data(self):
        return {}

    def test_upload_is_served_and_retry_is_a_no_op(self, api_client, create_data, auto_master):
        client = api_client(roles.OPERATOR)
        first = client.post(self.list_url(), create_data, format="multipart")
        assert first.status_code == 201
        assert first.json()["image"].endswith(".jpg")
        create_data["image"] = upload(name="front.jpg", fmt="JPEG")
        retry = client.post(self.list_url(), create_data, format="multipart")
        assert retry.status_code == 200 and retry.json()["id"] == first.json()["id"]

    def test_not_an_image_is_refused(self, api_client, create_data):
        from django.core.files.uploadedfile import SimpleUploadedFile

        create_data["image"] = SimpleUploadedFile("x.jpg", b"\xff\xd8 not really", "image/jpeg")
        response = api_client(roles.OPERATOR).post(self.list_url(), create_data, format="multipart")
        assert "image" in assert_error_shape(response, 400)["errors"]
