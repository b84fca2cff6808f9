"""Did the robot drive the same route: deviation and Fréchet distance between legs."""

import math
from datetime import timedelta

import pytest
from pyproj import Geod

from common import roles
from events.models import SegmentType
from events.services import logs, segments
from telemetry.services import recording

# A straight run eastwards, 2 m apart, about 100 m long.
EAST = [(7.1 + i * 2.8e-5, 50.6) for i in range(51)]
# Five metres on the WGS84 meridian at 50.6° north, in degrees of latitude.
FIVE_METRES_NORTH = 5.0 / 111_217.4


def drive(shift, points):
    """A new leg of ``shift`` with one AUTO segment along ``points`` (stamped 1 s apart)."""
    leg = logs.create_leg(shift=shift)
    master = segments.report_mode(leg, SegmentType.AUTO).master
    start = master.start
    fixes = [
        recording.GpsFix(lon, lat, robot_stamp=start + timedelta(seconds=i))
        for i, (lon, lat) in enumerate(points)
    ]
    recording.record_poses(master, fixes)
    return leg


@pytest.fixture
def compare(api_client):
    client = api_client(roles.VIEWER)

    def run(*legs, **query):
        response = client.get("/api/reports/routes/", {"leg": [leg.pk for leg in legs], **query})
        assert response.status_code == 200, response.content
        return response.json()

    return run


def test_a_route_against_itself_deviates_by_nothing(compare, shift):
    leg = drive(shift, EAST)
    again = drive(shift, EAST)
    pair = compare(leg, again)["pairs"][0]
    assert pair["frechet"] == pytest.approx(0.0, abs=1e-6)
    for side in pair["deviation"].values():
        assert side["max"] == pytest.approx(0.0, abs=1e-6)
        assert side["beyond"] == []


def test_a_copy_five_metres_north_deviates_by_five_metres_everywhere(compare, shift):
    leg = drive(shift, EAST)
    north = drive(shift, [(lon, lat + FIVE_METRES_NORTH) for lon, lat in EAST])
    pair = compare(leg, north, threshold=4.5)["pairs"][0]
    for side in pair["deviation"].values():
        for figure in ("mean", "p95", "max"):
            assert side[figure] == pytest.approx(5.0, abs=0.1)
        assert side["share_beyond"] == 1.0
        assert len(side["beyond"]) == 1 and len(side["beyond"][0]) == len(EAST)
    assert pair["frechet"] == pytest.approx(5.0, abs=0.1)
    # Under the threshold nothing is drawn as a deviation.
    quiet = compare(leg, north, threshold=5.5)["pairs"][0]
    assert all(side["beyond"] == [] for side in quiet["deviation"].values())


def test_the_same_route_driven_backwards_is_as_far_as_its_length(compare, shift):
    leg = drive(shift, EAST)
    back = drive(shift, list(reversed(EAST)))
    pair = compare(leg, back)["pairs"][0]
    # Pointwise the lines coincide; in driving order the start is coupled to the
    # far end, so the discrete Fréchet distance is the route's length.
    assert all(side["max"] < 1e-6 for side in pair["deviation"].values())
    (lon0, lat0), (lon1, lat1) = EAST[0], EAST[-1]
    length = Geod(ellps="WGS84").inv(lon0, lat0, lon1, lat1)[2]
    assert pair["frechet"] == pytest.approx(length, abs=0.1)
    assert math.isclose(length, 100.0, rel_tol=0.02)


def test_a_detour_is_drawn_where_it_leaves_the_route(compare, shift):
    leg = drive(shift, EAST)
    detour = [
        (lon, lat + (4 * FIVE_METRES_NORTH if 20 <= i < 30 else 0))
        for i, (lon, lat) in enumerate(EAST)
    ]
    other = drive(shift, detour)
    side = compare(leg, other)["pairs"][0]["deviation"][f"leg {other.pk}"]
    assert side["max"] == pytest.approx(20.0, abs=0.2)
    assert len(side["beyond"]) == 1
    assert side["beyond"][0][0] == pytest.approx(list(detour[20]))
    assert len(side["beyond"][0]) == 10


def test_bad_requests_get_field_messages(api_client, shift):
    client = api_client(roles.VIEWER)
    leg = drive(shift, EAST)
    empty = logs.create_leg(shift=shift)
    cases = [
        ({"leg": [leg.pk]}, "leg", "at least two"),
        ({"leg": [leg.pk, 999999]}, "leg", "No leg with id 999999"),
        ({"leg": [leg.pk, empty.pk]}, "leg", "fewer than two GPS points"),
        ({"leg": [leg.pk, leg.pk], "threshold": "-3"}, "threshold", "above 0"),
        ({"leg": [leg.pk, leg.pk], "threshold": "nan"}, "threshold", "above 0"),
    ]
    for query, field, words in cases:
        response = client.get("/api/reports/routes/", query)
        assert response.status_code == 400, (query, response.content)
        assert words in " ".join(response.json()["errors"][field])
