"""GET /api/tracks/ and /api/local-tracks/: one line per master segment, in time order."""

from datetime import UTC, datetime, timedelta

import pytest

from common import roles
from events.models import SegmentType
from events.services import logs, segments
from telemetry.models.poses import FixStatus
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from tests.support.api import assert_error_shape

# After the fixtures opened the leg "now": the services refuse times before a parent starts.
T0 = datetime.now(UTC).replace(microsecond=0) + timedelta(hours=1)


def at(seconds):
    return T0 + timedelta(seconds=seconds)


@pytest.fixture
def driven_leg(leg):
    """AUTO then ITO; poses sent out of order, one ITO pose posted to the reason."""
    auto = segments.report_mode(leg, SegmentType.AUTO, at=at(0)).master
    pose_writes.store_poses(
        auto,
        [
            GpsFix(7.2, 50.2, robot_stamp=at(3)),
            GpsFix(7.0, 50.0, robot_stamp=at(1)),
            GpsFix(9.9, 9.9, robot_stamp=at(2), fix_status=FixStatus.NO_FIX),
            GpsFix(7.1, 50.1, robot_stamp=at(2)),
        ],
    )
    pose_writes.store_local_poses(
        auto,
        [MapPose(2.0, 0.0, "map", robot_stamp=at(2)), MapPose(0.0, 0.0, "map", robot_stamp=at(1))],
    )
    ito = segments.report_mode(leg, SegmentType.ITO, at=at(10)).master
    pose_writes.store_poses(ito.children.get(), [GpsFix(7.3, 50.3, robot_stamp=at(11))])
    pose_writes.store_poses(ito, [GpsFix(7.4, 50.4, robot_stamp=at(12))])
    return leg, auto, ito


def test_one_linestring_per_master_in_time_order(api_client, driven_leg):
    leg, auto, ito = driven_leg
    response = api_client(roles.VIEWER).get("/api/tracks/", {"leg": leg.pk})
    assert response.status_code == 200, response.content
    collection = response.json()
    assert collection["type"] == "FeatureCollection"
    features = collection["features"]
    assert [f["properties"]["segment"] for f in features] == [auto.pk, ito.pk]
    first, second = features
    assert first["geometry"] == {
        "type": "LineString",
        "coordinates": [[7.0, 50.0], [7.1, 50.1], [7.2, 50.2]],
    }
    assert first["properties"]["mode"] == "auto"
    assert first["properties"]["point_count"] == 3
    assert first["properties"]["uid"] == str(auto.uid)
    assert first["properties"]["end"] == ito.start.isoformat()
    assert second["geometry"]["coordinates"] == [[7.3, 50.3], [7.4, 50.4]]
    assert second["properties"]["mode"] == "ito" and second["properties"]["end"] is None


def test_tracks_of_a_shift_and_test_event_include_every_leg(api_client, driven_leg):
    leg, auto, ito = driven_leg
    later = logs.create_leg(shift=leg.shift, at=at(20))
    master = segments.report_mode(later, SegmentType.AUTO, at=at(21)).master
    pose_writes.store_poses(master, [GpsFix(8.0, 51.0)])
    client = api_client(roles.VIEWER)
    for query in ({"shift": leg.shift_id}, {"test_event": leg.shift.test_event_id}):
        features = client.get("/api/tracks/", query).json()["features"]
        assert [f["id"] for f in features] == [auto.pk, ito.pk, master.pk]
        # A single point cannot be a line.
        assert features[-1]["geometry"] == {"type": "Point", "coordinates": [8.0, 51.0]}


def test_local_tracks_are_x_and_y_arrays(api_client, driven_leg):
    leg, auto, _ = driven_leg
    tracks = api_client(roles.VIEWER).get("/api/local-tracks/", {"leg": leg.pk}).json()["tracks"]
    assert len(tracks) == 1
    assert tracks[0]["segment"] == auto.pk and tracks[0]["frame"] == "map"
    assert (tracks[0]["x"], tracks[0]["y"]) == ([0.0, 2.0], [0.0, 0.0])


@pytest.mark.parametrize(
    "query", [{}, {"leg": "x"}, {"leg": 10**30}, {"leg": 999999}, {"leg": 1, "shift": 1}]
)
def test_track_queries_need_exactly_one_existing_parent(api_client, leg, query):
    client = api_client(roles.VIEWER)
    assert_error_shape(client.get("/api/tracks/", query), 400)
    assert_error_shape(client.get("/api/local-tracks/", query), 400)


def test_tracks_need_a_role(api_client, leg):
    assert api_client(None).get("/api/tracks/", {"leg": leg.pk}).status_code == 403
    assert api_client(anonymous=True).get("/api/tracks/", {"leg": leg.pk}).status_code == 401
