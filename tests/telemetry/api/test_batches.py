"""Pose batches, small (one statement) and big (COPY on PostgreSQL): each pose is
stored once, exactly as sent, on the master; a wrong row stores nothing."""

import uuid
from datetime import UTC, datetime, timedelta

import pytest

from events.models import Announcement, SegmentType
from events.services import segments
from telemetry.models import LocalPose, Pose
from telemetry.storage.postgresql import COPY_FROM
from tests.support.api import assert_error_shape

T0 = datetime(2026, 5, 4, 8, tzinfo=UTC)
# Below and above the size from which PostgreSQL copies; SQLite takes both its one way.
SIZES = [3, COPY_FROM + 7]


def _gps(i):
    return {
        "uid": str(uuid.uuid4()),
        "longitude": 7.0 + i * 1e-6,
        "latitude": 50.0 - i * 1e-6,
        # Every other pose leaves out what is optional.
        **(
            {
                "altitude": 100.0 + i / 8,
                "fix_status": 2,
                "horizontal_accuracy": 0.01 * (i % 5),
                "robot_stamp": (T0 + timedelta(milliseconds=100 * i)).isoformat(),
            }
            if i % 2
            else {}
        ),
    }


def _local(i):
    return {
        "uid": str(uuid.uuid4()),
        "frame": "map" if i % 3 else "odom",
        "x": i * 0.5,
        "y": -i * 0.25,
        **(
            {"yaw": i * 0.01, "robot_stamp": (T0 + timedelta(seconds=i)).isoformat()}
            if i % 2
            else {}
        ),
    }


def _gps_as_stored(pose: Pose) -> dict:
    row = {
        "uid": str(pose.uid),
        "longitude": pose.point.x,
        "latitude": pose.point.y,
    }
    if pose.robot_stamp is not None:
        row.update(
            altitude=pose.altitude,
            fix_status=pose.fix_status,
            horizontal_accuracy=pose.horizontal_accuracy,
            robot_stamp=pose.robot_stamp.isoformat(),
        )
    else:
        assert (pose.altitude, pose.fix_status, pose.horizontal_accuracy) == (None, 0, None)
    return row


def _local_as_stored(pose: LocalPose) -> dict:
    row = {"uid": str(pose.uid), "frame": pose.frame, "x": pose.x, "y": pose.y}
    if pose.robot_stamp is not None:
        row.update(yaw=pose.yaw, robot_stamp=pose.robot_stamp.isoformat())
    else:
        assert pose.yaw is None
    return row


KINDS = {
    # url: (one pose, the model, a stored row in the shape sent, the feed's kind)
    "/api/poses/batch/": (_gps, Pose, _gps_as_stored, "poses"),
    "/api/local-poses/batch/": (_local, LocalPose, _local_as_stored, "local_poses"),
}


@pytest.fixture
def child(leg):
    """An ITO reason: its poses are stored on its master."""
    segments.report_mode(leg, SegmentType.AUTO)
    return segments.new_manual_segment(leg)


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("url", KINDS)
def test_a_batch_is_stored_once_as_sent_and_a_retry_stores_nothing(url, size, api_client, child):
    make, model, as_stored, kind = KINDS[url]
    client = api_client("operator")
    sent = [make(i) for i in range(size)]
    feed_before = Announcement.objects.filter(kind=kind).count()
    response = client.post(url, {"segment": child.pk, "poses": sent}, format="json")
    assert response.status_code == 201 and response.json() == {"stored": size}, response.content
    stored = model.objects.filter(uid__in=[p["uid"] for p in sent])
    assert {p.segment_id for p in stored} == {child.parent_id}
    by_uid = {str(p.uid): as_stored(p) for p in stored}
    assert [by_uid[p["uid"]] for p in sent] == sent
    announced = Announcement.objects.filter(kind=kind).order_by("-id").first()
    assert Announcement.objects.filter(kind=kind).count() == feed_before + 1
    assert announced.payload["count"] == size and announced.payload["segment"] == child.parent_id

    # Sent again (a lost answer), with two new poses among the known ones.
    more = [make(size + i) for i in range(2)]
    again = client.post(url, {"segment": child.pk, "poses": [*sent, *more]}, format="json")
    assert again.status_code == 201 and again.json() == {"stored": 2}, again.content
    assert model.objects.filter(segment=child.parent).count() == size + 2
    announced = Announcement.objects.filter(kind=kind).order_by("-id").first()
    assert announced.payload["count"] == 2
    # The stamped one of them was driven before the unstamped poses stored first
    # (driving order): the track changed inside, and browsers read it again.
    assert announced.payload["changed"] is True and "points" not in announced.payload

    # Sent a third time: nothing new, nothing announced.
    third = client.post(url, {"segment": child.pk, "poses": [*sent, *more]}, format="json")
    assert third.json() == {"stored": 0}
    assert Announcement.objects.filter(kind=kind).count() == feed_before + 2


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize(
    "url, bad, field",
    [
        ("/api/poses/batch/", {"latitude": 91}, "latitude"),
        ("/api/poses/batch/", {"fix_status": 5}, "fix_status"),
        ("/api/poses/batch/", {"robot_stamp": "yesterday"}, "robot_stamp"),
        ("/api/local-poses/batch/", {"x": "east"}, "x"),
        ("/api/local-poses/batch/", {"frame": ""}, "frame"),
    ],
)
def test_a_bad_row_names_row_and_field_and_stores_nothing(url, bad, field, size, api_client, child):
    make, model, _, _ = KINDS[url]
    poses = [make(i) for i in range(size)]
    row = size - 2
    poses[row].update(bad)
    response = api_client("operator").post(
        url, {"segment": child.pk, "poses": poses}, format="json"
    )
    body = assert_error_shape(response, 400)
    assert list(body["errors"]["poses"]) == [str(row)]
    assert list(body["errors"]["poses"][str(row)]) == [field]
    assert not model.objects.filter(segment=child.parent).exists()
