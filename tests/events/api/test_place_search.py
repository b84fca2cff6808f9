"""Where did it fail: take-overs found by place (polygon, box, across ±180°, with
holes), reason, vehicle and version, as a list, GeoJSON and CSV, on both databases."""

import csv
import io
import json
import math
from urllib.parse import urlencode

import pytest

from common import roles
from common.areas import MAX_CORNERS
from events.models import SegmentType, Vehicle
from events.services import logs, segments
from events.services.segments import GpsPosition
from tests.support.api import streamed

# On SpatiaLite too: spatial lookups compile to PostGIS or SpatiaLite functions.
pytestmark = pytest.mark.spatialite

SQUARE = [[7.0, 50.0], [8.0, 50.0], [8.0, 51.0], [7.0, 51.0], [7.0, 50.0]]
HOLE = [[7.4, 50.4], [7.6, 50.4], [7.6, 50.6], [7.4, 50.6], [7.4, 50.4]]
# Drawn eastwards over the antimeridian, as a map that wraps lets one draw it.
ACROSS = [[175.0, -10.0], [185.0, -10.0], [185.0, 10.0], [175.0, 10.0], [175.0, -10.0]]


@pytest.fixture
def take_overs(leg):
    """Take-overs at named places, each reason 'safety' except 'edge' ('planner')."""
    places = {
        "inside": (7.5, 50.5),
        "edge": (8.0, 50.25),
        "corner": (7.0, 51.0),
        "outside": (8.1, 50.5),
        "in_hole_ring": (7.3, 50.5),
        "east_of_180": (179.5, 0.0),
        "west_of_180": (-179.5, 0.0),
        "far_east": (170.0, 0.0),
        "far_west": (-170.0, 0.0),
    }
    found = {}
    for name, (lon, lat) in places.items():
        segments.report_mode(leg, SegmentType.AUTO)
        master = segments.report_mode(leg, SegmentType.ITO, gps=GpsPosition(lon, lat)).master
        child = master.children.get()
        segments.annotate_segment(child, ito_reason="planner" if name == "edge" else "safety")
        found[name] = master.pk
    return found


@pytest.fixture
def search(api_client):
    client = api_client(roles.VIEWER)

    def names(take_overs, **query):
        response = client.get("/api/segments/", {"master": "true", "mode": "ito", **query})
        assert response.status_code == 200, response.content
        ids = {row["id"] for row in response.json()["results"]}
        return sorted(name for name, pk in take_overs.items() if pk in ids)

    return names


def polygon(*rings):
    return json.dumps({"type": "Polygon", "coordinates": list(rings)})


def test_a_polygon_finds_the_take_overs_inside_and_on_its_edge(search, take_overs):
    assert search(take_overs, within=polygon(SQUARE)) == [
        "corner",
        "edge",
        "in_hole_ring",
        "inside",
    ]


def test_a_hole_in_the_polygon_is_left_out(search, take_overs):
    assert search(take_overs, within=polygon(SQUARE, HOLE)) == ["corner", "edge", "in_hole_ring"]


def test_areas_across_the_antimeridian(search, take_overs):
    expected = ["east_of_180", "west_of_180"]
    assert search(take_overs, within=polygon(ACROSS)) == expected
    assert search(take_overs, in_bbox="175,-10,-175,10") == expected
    # The same area as a GeoJSON Feature and as WKT.
    feature = {"type": "Feature", "geometry": json.loads(polygon(ACROSS)), "properties": {}}
    assert search(take_overs, within=json.dumps(feature)) == expected
    wkt = "POLYGON((175 -10, 185 -10, 185 10, 175 10, 175 -10))"
    assert search(take_overs, within=wkt) == expected


def test_place_combines_with_reason_vehicle_and_version(search, take_overs, leg):
    area = polygon(SQUARE)
    assert search(take_overs, within=area, reason="planner") == ["edge"]
    assert search(take_overs, within=area, reason="safety") == ["corner", "in_hole_ring", "inside"]
    assert search(take_overs, within=area, vehicle=leg.shift.vehicle_id) != []
    other = Vehicle.objects.create(key="other", short_description="Other robot")
    assert search(take_overs, within=area, vehicle=other.pk) == []
    logs.update_test_event(leg.shift.test_event, version="2.3.1")
    assert search(take_overs, within=area, version="2.3.1", reason="planner") == ["edge"]
    assert search(take_overs, within=area, version="2.4") == []


@pytest.mark.parametrize(
    "bad, words",
    [
        ("nonsense", "GeoJSON or WKT polygon"),
        (json.dumps({"type": "Point", "coordinates": [7, 50]}), "polygon, not a Point"),
        (polygon([[7, 50], [8, 51], [8, 50], [7, 51], [7, 50]]), "not a valid polygon"),
        (polygon([[7, 95], [8, 95], [8, 96], [7, 95]]), "within ±90°"),
    ],
)
def test_a_bad_area_is_a_field_message(api_client, db, bad, words):
    response = api_client(roles.VIEWER).get("/api/segments/", {"within": bad})
    assert response.status_code == 400
    assert words in " ".join(response.json()["errors"]["within"])


def test_found_take_overs_download_as_geojson_and_csv(api_client, take_overs):
    client = api_client(roles.VIEWER)
    query = {"master": "true", "mode": "ito", "within": polygon(SQUARE, HOLE)}
    geo = client.get("/api/segments/found/", query)
    assert geo.status_code == 200 and geo["Content-Type"] == "application/geo+json"
    features = json.loads(streamed(geo))["features"]
    by_id = {f["id"]: f for f in features}
    assert set(by_id) == {take_overs[n] for n in ("corner", "edge", "in_hole_ring")}
    assert by_id[take_overs["edge"]]["geometry"]["coordinates"] == [8.0, 50.25]
    assert by_id[take_overs["edge"]]["properties"]["reason"] == "planner"
    assert by_id[take_overs["edge"]]["properties"]["mode"] == "ITO"
    # Numbered among every master of the leg, found or not: an AUTO before each take-over.
    labels = {n: by_id[pk]["properties"]["label"] for n, pk in take_overs.items() if pk in by_id}
    assert labels == {"edge": "Leg 1 · #4", "corner": "Leg 1 · #6", "in_hole_ring": "Leg 1 · #10"}

    sheet = client.get("/api/segments/found/", {**query, "as": "csv"})
    assert sheet.status_code == 200
    rows = list(csv.DictReader(io.StringIO(streamed(sheet).decode())))
    assert {int(r["id"]) for r in rows} == set(by_id)
    edge = next(r for r in rows if int(r["id"]) == take_overs["edge"])
    assert (float(edge["longitude"]), float(edge["latitude"])) == (8.0, 50.25)
    assert edge["label"].startswith("Leg 1 · #")

    wrong = client.get("/api/segments/found/", {**query, "as": "kml"})
    assert wrong.status_code == 400 and "geojson" in wrong.json()["errors"]["as"][0]


def test_a_reason_found_without_its_take_over_is_numbered_under_it(api_client, take_overs):
    client = api_client(roles.VIEWER)
    found = client.get("/api/segments/found/", {"master": "false", "reason": "planner"})
    assert found.status_code == 200
    (feature,) = json.loads(streamed(found))["features"]
    assert feature["properties"]["label"] == "Leg 1 · #4.1"
    assert feature["properties"]["reason"] == "planner"
    assert feature["properties"]["mode"] == "ITO"


def ring_of(vertices: int, lon=7.5, lat=50.5, radius=0.45):
    ring = [
        [
            lon + radius * math.cos(2 * math.pi * i / vertices),
            lat + radius * math.sin(2 * math.pi * i / vertices),
        ]
        for i in range(vertices)
    ]
    return [*ring, ring[0]]


def test_a_large_area_is_searched_by_post(api_client, take_overs):
    # About 80 KB of GeoJSON: more than an address may carry.
    area = {"type": "Polygon", "coordinates": [ring_of(2000)]}
    assert len(json.dumps(area)) > 65536
    client = api_client(roles.VIEWER)
    search = {"master": True, "mode": "ito", "within": area}
    geo = client.post("/api/segments/found/", search, format="json")
    assert geo.status_code == 200, geo.content
    found = {f["id"] for f in json.loads(streamed(geo))["features"]}
    assert found == {take_overs["inside"], take_overs["in_hole_ring"]}
    # As the page's download links send it: a form, the area as GeoJSON text.
    form = {"master": "true", "mode": "ito", "within": json.dumps(area), "as": "csv"}
    form["csrfmiddlewaretoken"] = "the page's token"
    sheet = client.post(
        "/api/segments/found/", urlencode(form), content_type="application/x-www-form-urlencoded"
    )
    assert sheet.status_code == 200
    assert {int(r["id"]) for r in csv.DictReader(io.StringIO(streamed(sheet).decode()))} == found


def test_a_bad_area_sent_by_post_is_a_field_message(api_client, db):
    bow_tie = {"type": "Polygon", "coordinates": [[[7, 50], [8, 51], [8, 50], [7, 51], [7, 50]]]}
    answer = api_client(roles.VIEWER).post(
        "/api/segments/found/", {"within": bow_tie}, format="json"
    )
    assert answer.status_code == 400
    assert "not a valid polygon" in " ".join(answer.json()["errors"]["within"])
    listed = api_client(roles.VIEWER).post("/api/segments/found/", [1, 2], format="json")
    assert listed.status_code == 400 and listed.json()["errors"]


def test_an_area_nested_too_deeply_is_a_field_message(api_client, db):
    deep = "[" * 100_000 + "]" * 100_000
    answer = api_client(roles.VIEWER).get("/api/segments/", {"within": deep})
    assert answer.status_code == 400
    assert "nested too deeply" in " ".join(answer.json()["errors"]["within"])


def test_an_area_of_more_than_twenty_thousand_corners_is_refused(api_client, take_overs):
    client = api_client(roles.VIEWER)
    search = {"master": True, "mode": "ito"}
    most = {"type": "Polygon", "coordinates": [ring_of(MAX_CORNERS)]}
    found = client.post("/api/segments/found/", {**search, "within": most}, format="json")
    assert found.status_code == 200, found.content
    ids = {f["id"] for f in json.loads(streamed(found))["features"]}
    assert ids == {take_overs["inside"], take_overs["in_hole_ring"]}
    # The corners of every ring and part count: here one more than the limit in two parts.
    half = MAX_CORNERS // 2
    parts = [[ring_of(half, radius=0.2)], [ring_of(half + 1, lon=9.5, radius=0.2)]]
    too_many = {"type": "MultiPolygon", "coordinates": parts}
    answer = client.post("/api/segments/found/", {**search, "within": too_many}, format="json")
    assert answer.status_code == 400
    assert "20001 corners; give at most 20000" in " ".join(answer.json()["errors"]["within"])
