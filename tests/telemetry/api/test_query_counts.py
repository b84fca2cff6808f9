"""Robot-data lists and tracks run a fixed number of queries, however many rows."""

import re
import uuid

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events import feed
from events.models import Announcement, Segment, SegmentType
from events.services import segments
from telemetry.models import Pose
from telemetry.services import attachments, map_images, pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.storage.postgresql import COPY_FROM
from tests.support.api import LIST_QUERIES, assert_constant_queries, post_counting_queries
from tests.support.images import png
from tests.support.modes import start_auto

# On SpatiaLite too: poses, figures and tracks are stored by the SQL of each database.
pytestmark = pytest.mark.spatialite


def _poses(n, leg):
    master = start_auto(leg)
    pose_writes.store_poses(master, [GpsFix(7 + i / 1000, 50.0) for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _local_poses(n, leg):
    master = start_auto(leg)
    pose_writes.store_local_poses(master, [MapPose(i, 0.0, "map") for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _maps(n, leg):
    for _ in range(n):
        map_images.store_map(
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
    master = start_auto(leg)
    for _ in range(n):
        attachments.attach_image(master, content=png(fmt="JPEG"))


CASES = {
    "/api/poses/": (_poses, LIST_QUERIES),
    "/api/local-poses/": (_local_poses, LIST_QUERIES),
    "/api/maps/": (_maps, LIST_QUERIES),
    "/api/images/": (_images, LIST_QUERIES),
    # The leg, its masters, their points: more segments add none.
    # GPS and local points on PostGIS are one query in a transaction whose first
    # statement reads the stored span and switches JIT off (savepoint, span, query,
    # release: telemetry/storage/postgresql.py).
    "/api/tracks/?leg={leg}": (_poses, 6),
    "/api/local-tracks/?leg={leg}": (_local_poses, 6),
    "/api/tracks/?shift={shift}": (_poses, 6),
    "/api/tracks/?test_event={test_event}": (_poses, 6),
    "/api/local-tracks/?shift={shift}": (_local_poses, 6),
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


@pytest.fixture(autouse=True)
def _no_pruning(monkeypatch):
    """Every PRUNE_EVERY-th feed row also prunes the feed: not what is counted here."""
    monkeypatch.setattr(feed, "PRUNE_EVERY", 10**12)


def _pose(segment, **fields):
    return {"segment": segment.pk, "longitude": 7.1, "latitude": 50.2, **fields}


def _one_post(client, body):
    with CaptureQueriesContext(connection) as captured:
        response = client.post("/api/poses/", body, format="json")
    return response, [q["sql"] for q in captured.captured_queries]


# Committed for real, as a server runs it: no test-wide transaction around it.
@pytest.mark.django_db(transaction=True)
def test_a_single_pose_is_one_short_transaction_of_two_statements(api_client, leg):
    """The pose (its segment and pose source checked, and refused for a final
    test event, in the same statement), then its segment's figures and its
    feed row: one statement on PostgreSQL, two on SpatiaLite (no insert
    inside a WITH there)."""
    child = segments.new_manual_segment(leg)
    master = child.parent
    client = api_client("operator")
    # The first pose also reads the token and the segment; both are kept.
    assert client.post("/api/poses/", _pose(child), format="json").status_code == 201
    body = _pose(child, uid=str(uuid.uuid4()), altitude=101.5, horizontal_accuracy=0.2)
    response, every, in_transaction = post_counting_queries(client, "/api/poses/", body)
    assert response.status_code == 201, response.content
    assert len(every) == len(in_transaction) + 2, every  # nothing outside it
    pose, *rest = in_transaction
    assert pose.split("INSERT INTO ", 1)[1].split()[0] == "telemetry_pose", pose
    assert '"events_testevent"."finalised" IS NOT NULL' in pose, pose
    # The figures brought up to date in one upsert (it locks their row), then
    # the feed row: the lock orders one master's rows as their commits.
    if connection.vendor == "postgresql":
        assert len(rest) == 1, rest
        tables = re.findall(r"INSERT INTO (\S+)", rest[0])
        assert tables == ["telemetry_segmentfigures", "rosbridge_app_announcement"], rest
    else:
        assert [q.split("INSERT INTO ", 1)[1].split()[0] for q in rest] == [
            "telemetry_segmentfigures",
            '"rosbridge_app_announcement"',
        ], rest
    stored = Pose.objects.get(uid=body["uid"])
    assert (stored.segment_id, stored.point.x, stored.point.y) == (master.pk, 7.1, 50.2)
    assert (stored.altitude, stored.horizontal_accuracy) == (101.5, 0.2)
    assert stored.pose_source_id == leg.default_pose_source_id
    # The answer is the stored row as the pose list shows it.
    listed = client.get("/api/poses/", {"segment": master.pk, "page_size": 10}).json()["results"]
    assert response.json() == next(p for p in listed if p["uid"] == body["uid"])
    assert response.json()["id"] == stored.pk
    assert response.json()["segment"] == master.pk
    assert response.json()["received"] is not None
    assert response.json()["pose_source"] == leg.default_pose_source_id
    announced = Announcement.objects.order_by("-id").first()
    assert announced.kind == "poses" and announced.leg_id == leg.pk
    assert announced.payload["segment"] == master.pk and announced.payload["points"] == [
        [7.1, 50.2]
    ]

    feed_rows = Announcement.objects.count()
    again, every, in_transaction = post_counting_queries(client, "/api/poses/", body)
    assert again.status_code == 200 and again.json() == response.json()
    assert Pose.objects.filter(uid=body["uid"]).count() == 1
    assert Announcement.objects.count() == feed_rows  # nothing new to announce
    # The insert, whether the event is final (why nothing was stored), then
    # the row stored first.
    assert len(in_transaction) == 2 and len(every) == 5, every


def test_a_robots_single_pose_costs_what_an_operators_does(api_client, robot_client, vehicle, leg):
    """The robot's vehicles are read on its first request and kept, like its token."""
    master = start_auto(leg)
    counts = {}
    for name, client in (("operator", api_client("operator")), ("robot", robot_client(vehicle))):
        first, first_queries = _one_post(client, _pose(master))
        assert first.status_code == 201, first.content
        response, queries = _one_post(client, _pose(master))
        assert response.status_code == 201, response.content
        counts[name] = (len(first_queries), len(queries))
    assert counts["robot"][1] == counts["operator"][1], counts
    assert counts["robot"][1] < counts["robot"][0], counts


@pytest.mark.parametrize(
    "body, status, field",
    [
        ({"segment": 999999999, "longitude": 7.1, "latitude": 50.2}, 400, "segment"),
        ({"longitude": 7.1, "latitude": 50.2, "pose_source": 999999999}, 400, "pose_source"),
        ({"longitude": 7.1, "latitude": 95.0}, 400, "latitude"),
        ({"segment": "7", "longitude": 7.1, "latitude": 50.2, "fix_status": 9}, 400, "fix_status"),
    ],
)
def test_a_refused_single_pose_names_its_field_and_stores_nothing(
    body, status, field, api_client, auto_master
):
    client = api_client("operator")
    assert client.post("/api/poses/", _pose(auto_master), format="json").status_code == 201
    before = Pose.objects.count()
    response = client.post("/api/poses/", {"segment": auto_master.pk, **body}, format="json")
    assert response.status_code == status, response.content
    assert field in response.json()["errors"], response.json()
    assert Pose.objects.count() == before


def test_a_robot_may_not_post_a_pose_to_another_vehicles_segment(
    robot_client, vehicle, leg, other_leg
):
    client = robot_client(vehicle)
    own = start_auto(leg)
    assert client.post("/api/poses/", _pose(own), format="json").status_code == 201
    other = start_auto(other_leg)
    response = client.post("/api/poses/", _pose(other), format="json")
    assert response.status_code == 403, response.content
    assert "belongs to vehicle jackal" in response.json()["detail"]
    assert not Pose.objects.filter(segment=other).exists()


def test_a_deleted_segment_is_noticed_although_it_was_kept(api_client, leg):
    master = start_auto(leg)
    client = api_client("operator")
    assert client.post("/api/poses/", _pose(master), format="json").status_code == 201
    # Deleted behind this process's back (another worker, the admin of another process).
    Segment.objects.filter(pk=master.pk).delete()
    response = client.post("/api/poses/", _pose(master), format="json")
    assert response.status_code == 400, response.content
    assert "segment" in response.json()["errors"]


# SQLite splits long statements by its variable limit; PostgreSQL takes one array per
# column below COPY_FROM and copies from there on.
@pytest.mark.postgis_only
@pytest.mark.parametrize(
    "size, queries",
    [
        # The insert of unnested arrays (refused for a final test event in the
        # same statement), the segment's figures (read, then updated in the
        # statement that adds the feed row).
        (10, 3),
        # The same with the staging table, COPY and the insert from it.
        (COPY_FROM, 5),
        (5000, 5),
    ],
)
def test_a_batch_costs_the_same_queries_whatever_its_size(size, queries, api_client, auto_master):
    client = api_client("operator")
    poses = [{"longitude": 7.0, "latitude": 50.0 + i * 1e-6} for i in range(size)]
    body = {"segment": auto_master.pk, "poses": poses}
    response, _, in_transaction = post_counting_queries(client, "/api/poses/batch/", body)
    assert response.status_code == 201 and response.json() == {"stored": size}
    assert len(in_transaction) == queries, in_transaction
    assert Pose.objects.filter(segment=auto_master).count() == size
