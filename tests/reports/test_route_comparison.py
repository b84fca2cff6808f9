"""Did the robot drive the same route: deviation and Fréchet distance between legs,
and a leg and a test case's planned route, in the API and in the comparison PDF."""

import math
from datetime import timedelta

import pytest
from django.contrib.gis.geos import LineString
from pypdf import PdfReader
from pyproj import Geod

from common import roles
from events.models import SegmentType, TestCase
from events.services import logs, segments
from reports.models import Report
from reports.services.generation import run_job
from telemetry.services import recording
from tests.support.pdf import has_row, pdf_text, save_pages

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


def planned(shift, points, key="loop"):
    route = LineString(points, srid=4326) if points else None
    return TestCase.objects.create(test_event=shift.test_event, key=key, title=key, route=route)


def test_a_leg_against_its_planned_route_five_metres_north(api_client, shift):
    leg = drive(shift, EAST)
    # The plan is the straight line only, its two ends: it is measured every metre.
    case = planned(shift, [(lon, lat + FIVE_METRES_NORTH) for lon, lat in (EAST[0], EAST[-1])])
    response = api_client(roles.VIEWER).get(
        "/api/reports/routes/", {"leg": leg.pk, "case": case.pk, "threshold": 4.5}
    )
    assert response.status_code == 200, response.content
    answer = response.json()
    assert set(answer["routes"]) == {f"leg {leg.pk}", f"case {case.pk}"}
    assert 100 <= len(answer["routes"][f"case {case.pk}"]) <= 102
    pair = answer["pairs"][0]
    assert pair["routes"] == [f"leg {leg.pk}", f"case {case.pk}"]
    for side in pair["deviation"].values():
        for figure in ("mean", "p95", "max"):
            assert side[figure] == pytest.approx(5.0, abs=0.1)
        assert side["share_beyond"] == 1.0
    assert pair["frechet"] == pytest.approx(5.0, abs=0.1)


def test_bad_requests_get_field_messages(api_client, shift):
    client = api_client(roles.VIEWER)
    leg = drive(shift, EAST)
    empty = logs.create_leg(shift=shift)
    unplanned = planned(shift, None)
    cases = [
        ({"leg": [leg.pk]}, "leg", "at least two"),
        ({"leg": [leg.pk, 999999]}, "leg", "No leg with id 999999"),
        ({"leg": [leg.pk, empty.pk]}, "leg", "fewer than two GPS points"),
        ({"leg": [leg.pk, leg.pk], "threshold": "-3"}, "threshold", "above 0"),
        ({"leg": [leg.pk, leg.pk], "threshold": "nan"}, "threshold", "above 0"),
        ({"leg": [leg.pk], "case": [999999]}, "case", "No test case with id 999999"),
        ({"leg": [leg.pk], "case": [unplanned.pk]}, "case", "has no planned route"),
        ({"leg": [leg.pk], "case": ["x"]}, "case", "numbers"),
    ]
    for query, field, words in cases:
        response = client.get("/api/reports/routes/", query)
        assert response.status_code == 400, (query, response.content)
        assert words in " ".join(response.json()["errors"][field])


def metres(value: float) -> str:
    return f"{value:.2f} m"


def test_the_comparison_pdf_overlays_a_leg_and_its_planned_route(api_client, shift, tmp_path):
    leg = drive(shift, EAST)
    case = planned(shift, [(lon, lat + FIVE_METRES_NORTH) for lon, lat in (EAST[0], EAST[-1])])
    other = logs.create_test_event(location="Elsewhere")
    routes = {"leg": [leg.pk], "case": [case.pk], "threshold": 4.5}
    operator = api_client(roles.OPERATOR)
    response = operator.post(
        "/api/reports/",
        {"compare": [shift.test_event.pk, other.pk], "options": {"routes": routes}},
        format="json",
    )
    assert response.status_code == 202, response.content
    report = run_job(response.json()["id"])
    assert report.status == Report.Status.DONE, report.error
    pdf = b"".join(operator.get(f"/api/reports/{report.pk}/pdf/").streaming_content)
    save_pages(pdf, "comparison-routes")
    text = pdf_text(pdf, tmp_path)
    assert "Routes" in text
    assert has_row(text, "A", "blue", f"Test event {shift.test_event.pk}, shift")
    assert has_row(text, "B", "orange", f"Test case {case.key}: {case.title} (planned)")
    # The overlay map is a picture on the routes' page (the charts are vector drawings).
    path = tmp_path / "routes.pdf"
    path.write_bytes(pdf)
    pictures = [p for page in PdfReader(str(path)).pages for p in page.images]
    assert len(pictures) == 1 and pictures[0].image.width > 500
    api = api_client(roles.VIEWER).get(
        "/api/reports/routes/", {"leg": leg.pk, "case": case.pk, "threshold": 4.5}
    )
    pair = api.json()["pairs"][0]
    for letter, other_letter, name in (("A", "B", f"leg {leg.pk}"), ("B", "A", f"case {case.pk}")):
        side = pair["deviation"][name]
        assert has_row(
            text,
            f"{letter} from {other_letter}",
            metres(pair["frechet"]),
            metres(side["mean"]),
            metres(side["p95"]),
            metres(side["max"]),
            "100.0 %",
        ), (letter, text)
        assert abs(side["mean"] - 5.0) < 0.1


def test_a_comparison_with_routes_it_cannot_draw_is_refused_before_queueing(api_client, shift):
    leg = drive(shift, EAST)
    unplanned = planned(shift, None)
    other = logs.create_test_event(location="Elsewhere")
    operator = api_client(roles.OPERATOR)
    for routes, words in (
        ({"leg": [leg.pk]}, "at least two routes"),
        ({"leg": [leg.pk], "case": [unplanned.pk]}, "has no planned route"),
        ({"leg": [leg.pk, 999999]}, "No leg with id 999999"),
        ({"leg": [leg.pk, "x"]}, "ids (numbers)"),
        ({"leg": [leg.pk, leg.pk], "threshold": 0}, "above 0"),
        ([leg.pk], "an object"),
    ):
        response = operator.post(
            "/api/reports/",
            {"compare": [shift.test_event.pk, other.pk], "options": {"routes": routes}},
            format="json",
        )
        assert response.status_code == 400, routes
        assert words in " ".join(response.json()["errors"]["options"]), response.json()
    assert Report.objects.count() == 0
