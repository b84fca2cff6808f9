"""Did the robot drive the same route: deviation and Fréchet distance between legs,
and a leg and a test case's planned route, in the API and in the comparison PDF."""

import math
from datetime import timedelta

import pytest
from django.contrib.gis.geos import LineString
from django.core.management import call_command
from django.core.management.base import CommandError
from pypdf import PdfReader
from pyproj import Geod

from common import roles
from events.models import SegmentType, TestCase
from events.services import logs, segments
from reports.models import Report
from reports.services.generation import run_job
from telemetry.services import pose_writes
from tests.support.pdf import flat, has_row, pdf_text, save_pages

GEOD = Geod(ellps="WGS84")
# A straight run eastwards along the parallel, fixes 1.98 m apart, 99.1 m long.
EAST = [(7.1 + i * 2.8e-5, 50.6) for i in range(51)]
SPACING = GEOD.inv(*EAST[0], *EAST[1])[2]
# Five metres north on the WGS84 ellipsoid, in degrees of latitude.
FIVE_METRES_NORTH = GEOD.fwd(*EAST[0], 0.0, 5.0)[1] - EAST[0][1]
# Lengths measured in the comparison's local frame against the ellipsoid's: the
# frame's scale error is below 1e-7 (reports/projection.py), and a planned line,
# straight in its own frame, bows from the parallel by L²·tan(φ)/(8R) = 0.2 mm
# over these 99 m. Both far below a millimetre.
MM = 1e-3


def drive(shift, points):
    """A new leg of ``shift`` with one AUTO segment along ``points`` (stamped 1 s apart)."""
    leg = logs.create_leg(shift=shift)
    master = segments.report_mode(leg, SegmentType.AUTO).master
    start = master.start
    fixes = [
        pose_writes.GpsFix(lon, lat, robot_stamp=start + timedelta(seconds=i))
        for i, (lon, lat) in enumerate(points)
    ]
    pose_writes.store_poses(master, fixes)
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
            assert side[figure] == pytest.approx(5.0, abs=MM)
        assert side["share_beyond"] == 1.0
        assert len(side["beyond"]) == 1 and len(side["beyond"][0]) == len(EAST)
    # Each fix is coupled with its copy, 5 m north of it.
    assert pair["frechet"] == pytest.approx(5.0, abs=MM)
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
    assert pair["frechet"] == pytest.approx(length, abs=MM)
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
    # The plan's 99.1 m in ceil(99.1) = 100 equal parts: half the leg's spacing, so
    # every other planned point lies north of a fix and the rest halfway between two.
    assert len(answer["routes"][f"case {case.pk}"]) == 2 * (len(EAST) - 1) + 1
    pair = answer["pairs"][0]
    assert pair["routes"] == [f"leg {leg.pk}", f"case {case.pk}"]
    for side in pair["deviation"].values():
        for figure in ("mean", "p95", "max"):
            assert side[figure] == pytest.approx(5.0, abs=MM)
        assert side["share_beyond"] == 1.0
    # The discrete Fréchet distance couples points with points, never with the line
    # between two: a planned point halfway between two fixes is coupled at best with
    # one of them, 5 m south and half a spacing along. Not 5 m but 5.10 m.
    assert pair["frechet"] == pytest.approx(math.hypot(5.0, SPACING / 2), abs=MM)


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


def assert_routes_section(text: str, api: dict, titles: list[str]) -> None:
    """The PDF's routes section: a legend row per route (A blue, B orange, C green)
    with its title, and per pair and direction the API's figures to the centimetre."""
    assert "Routes" in text
    names = list(api["routes"])
    letters = {name: chr(ord("A") + i) for i, name in enumerate(names)}
    colours = ("blue", "orange", "green")[: len(names)]
    for name, colour, title in zip(names, colours, titles, strict=True):
        assert has_row(text, letters[name], colour, title), (name, text)
    for pair in api["pairs"]:
        for name, other in (pair["routes"], reversed(pair["routes"])):
            side = pair["deviation"][name]
            assert has_row(
                text,
                f"{letters[name]} from {letters[other]}",
                metres(pair["frechet"]),
                *(metres(side[key]) for key in ("mean", "p95", "max")),
                f"{100 * side['share_beyond']:.1f} %",
            ), (name, other, text)


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
    # The overlay map is a picture on the routes' page (the charts are vector drawings).
    path = tmp_path / "routes.pdf"
    path.write_bytes(pdf)
    pictures = [p for page in PdfReader(str(path)).pages for p in page.images]
    assert len(pictures) == 1 and pictures[0].image.width > 500
    api = api_client(roles.VIEWER).get(
        "/api/reports/routes/", {"leg": leg.pk, "case": case.pk, "threshold": 4.5}
    )
    assert_routes_section(
        text,
        api.json(),
        [
            f"Test event {shift.test_event.pk}, shift",
            f"Test case {case.key}: {case.title} (planned)",
        ],
    )
    assert "100.0 %" in text  # 5 m apart, all beyond 4.5 m


def test_ftt_report_compare_draws_the_routes_asked_for(api_client, shift, tmp_path):
    leg = drive(shift, EAST)
    north = drive(shift, [(lon, lat + FIVE_METRES_NORTH) for lon, lat in EAST])
    case = planned(shift, [EAST[0], EAST[-1]])
    other = logs.create_test_event(location="Elsewhere")
    output = tmp_path / "comparison.pdf"
    call_command(
        "ftt_report",
        "--compare",
        str(shift.test_event.pk),
        str(other.pk),
        *("--route-leg", str(leg.pk), "--route-leg", str(north.pk)),
        *("--route-case", str(case.pk), "--route-threshold", "2.5"),
        "-o",
        str(output),
    )
    api = api_client(roles.VIEWER).get(
        "/api/reports/routes/", {"leg": [leg.pk, north.pk], "case": case.pk, "threshold": 2.5}
    )
    text = pdf_text(output.read_bytes(), tmp_path)
    assert "more than 2.50 m" in flat(text)
    event = f"Test event {shift.test_event.pk}, shift {shift.number}"
    assert_routes_section(
        text,
        api.json(),
        [f"{event}, leg {leg.number}", f"{event}, leg {north.number}", "Test case loop: loop"],
    )
    # In German the routes are named in German too.
    call_command(
        "ftt_report",
        "--compare",
        str(shift.test_event.pk),
        str(other.pk),
        "--route-leg",
        str(leg.pk),
        "--route-case",
        str(case.pk),
        "--language",
        "de",
        "-o",
        str(output),
    )
    text = pdf_text(output.read_bytes(), tmp_path)
    event = f"Testveranstaltung {shift.test_event.pk}, Schicht {shift.number}"
    assert has_row(text, "A", "blau", f"{event}, Etappe {leg.number}"), text
    assert has_row(text, "B", "orange", "Testfall loop: loop (geplant)"), text


def test_ftt_report_refuses_routes_it_cannot_draw(shift, tmp_path):
    leg = drive(shift, EAST)
    empty = logs.create_leg(shift=shift)
    other = logs.create_test_event(location="Elsewhere")
    compare = ["--compare", str(shift.test_event.pk), str(other.pk), "-o", str(tmp_path / "c.pdf")]
    for extra, words in (
        (["--route-leg", str(leg.pk)], "at least two routes"),
        (["--route-leg", str(leg.pk), "--route-leg", "999999"], "No leg with id 999999"),
        (["--route-leg", str(leg.pk), "--route-case", "999999"], "No test case with id 999999"),
        ([*("--route-leg", str(leg.pk)) * 2, "--route-threshold", "0"], "above 0"),
        ([*("--route-leg", str(leg.pk)) * 2, "--route-threshold", "nan"], "above 0"),
        (["--route-leg", str(leg.pk), "--route-leg", str(empty.pk)], "fewer than two GPS"),
    ):
        with pytest.raises(CommandError, match=words):
            call_command("ftt_report", *compare, *extra)
    with pytest.raises(CommandError, match="go with --compare"):
        call_command("ftt_report", "--test-event", str(other.pk), "--route-leg", str(leg.pk))
    assert not (tmp_path / "c.pdf").exists()


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
