"""Robot-data lists and tracks run a fixed number of queries, however many rows."""

import uuid

import pytest

from events.models import SegmentType
from events.services import segments
from telemetry.models import Pose
from telemetry.services import recording
from telemetry.services.recording import GpsFix, MapPose
from tests.support.api import LIST_QUERIES, assert_constant_queries, post_counting_queries
from tests.support.images import png


def _poses(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    recording.record_poses(master, [GpsFix(7 + i / 1000, 50.0) for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _local_poses(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    recording.record_local_poses(master, [MapPose(i, 0.0, "map") for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _maps(n, leg):
    for _ in range(n):
        recording.record_map(
            leg.shift,
            png=png(colour=(len(leg.shift.maps.all()), 0, 0)),
            frame="map",
            width=4,
            height=3,
            resolution=0.05,
            origin_x=0,
            origin_y=0,
        )


def _images(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    for _ in range(n):
        recording.attach_image(master, content=png(fmt="JPEG"))


CASES = {
    "/api/poses/": (_poses, LIST_QUERIES),
    "/api/local-poses/": (_local_poses, LIST_QUERIES),
    "/api/maps/": (_maps, LIST_QUERIES),
    "/api/images/": (_images, LIST_QUERIES),
    # Token + user, groups, the leg, its masters, their points: more segments add none.
    # GPS and local points on PostGIS are one query in a transaction that switches
    # JIT off (savepoint, SET LOCAL, query, release: telemetry/selectors/tracks.py).
    "/api/tracks/?leg={leg}": (_poses, 8),
    "/api/local-tracks/?leg={leg}": (_local_poses, 8),
    "/api/tracks/?shift={shift}": (_poses, 8),
    "/api/tracks/?test_event={test_event}": (_poses, 8),
    "/api/local-tracks/?shift={shift}": (_local_poses, 8),
}


@pytest.mark.parametrize("url", CASES)
def test_list_queries_do_not_grow_with_rows(
    url, api_client, django_assert_max_num_queries, leg, media_root
):
    add, most = CASES[url]
    assert_constant_queries(
        api_client,
        django_assert_max_num_queries,
        url.format(leg=leg.pk, shift=leg.shift_id, test_event=leg.shift.test_event_id),
        lambda n: add(n, leg),
        most=most,
    )


# Token with its user and groups, the segment with its master and leg; then the transaction.
AUTH_AND_SEGMENT = 2


def test_a_single_pose_is_one_short_transaction(api_client, leg):
    child = segments.new_manual_segment(leg)
    master = child.parent
    client = api_client("operator")
    body = {"segment": child.pk, "longitude": 7.1, "latitude": 50.2, "uid": str(uuid.uuid4())}
    response, every, in_transaction = post_counting_queries(client, "/api/poses/", body)
    assert response.status_code == 201, response.content
    # SQLite: the known uids, the insert, the feed row.  PostgreSQL folds the first
    # two into one insert and adds the NOTIFY that wakes the live pages.
    assert len(in_transaction) <= 3, in_transaction
    assert len(every) == AUTH_AND_SEGMENT + len(in_transaction) + 2, every
    stored = Pose.objects.get(uid=body["uid"])
    assert (stored.segment_id, stored.point.x, stored.point.y) == (master.pk, 7.1, 50.2)
    assert stored.pose_source_id == leg.default_pose_source_id
    assert response.json()["id"] == stored.pk
    assert response.json()["received"] is not None
    assert response.json()["pose_source"] == leg.default_pose_source_id

    again, _, _ = post_counting_queries(client, "/api/poses/", body)
    assert again.status_code == 200 and again.json() == response.json()
    assert Pose.objects.filter(uid=body["uid"]).count() == 1


def test_a_robot_adds_one_query_to_a_single_pose(api_client, robot_client, vehicle, leg):
    """The robot's vehicles, read once per request; the segment's vehicle comes with it."""
    master = segments.report_mode(leg, SegmentType.AUTO).master
    counts = {}
    for name, client in (("operator", api_client("operator")), ("robot", robot_client(vehicle))):
        body = {"segment": master.pk, "longitude": 7.1, "latitude": 50.2}
        response, every, in_transaction = post_counting_queries(client, "/api/poses/", body)
        assert response.status_code == 201, response.content
        counts[name] = (len(every), len(in_transaction))
    assert counts["robot"][1] == counts["operator"][1]
    assert counts["robot"][0] == counts["operator"][0] + 1, counts


# SQLite splits long statements by its variable limit; PostgreSQL takes one array per column.
@pytest.mark.postgis_only
# Committed for real: inside a test-wide transaction an earlier write of the
# fixtures would already have sent this transaction's one NOTIFY.
@pytest.mark.django_db(transaction=True)
@pytest.mark.parametrize("size", [10, 1000])
def test_a_batch_costs_the_same_queries_whatever_its_size(size, api_client, auto_master):
    client = api_client("operator")
    poses = [{"longitude": 7.0, "latitude": 50.0 + i * 1e-6} for i in range(size)]
    body = {"segment": auto_master.pk, "poses": poses}
    response, _, in_transaction = post_counting_queries(client, "/api/poses/batch/", body)
    assert response.status_code == 201 and response.json() == {"stored": size}
    assert len(in_transaction) == 3, in_transaction  # insert, feed row, NOTIFY
    assert Pose.objects.filter(segment=auto_master).count() == size
