"""The GUI's leg tracks thinned for the map's zoom, gzipped, with full-track distances."""

import gzip
import json

import pytest
from django.contrib.gis.geos import Point
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events.services import segments
from telemetry.selectors.track_drawing import zoom_tolerance
from telemetry.services import pose_writes
from tests.support.accounts import signed_in
from tests.support.caches import forget_cached_tracks
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db

# The area in view of a map zoomed in (docs/gui.md, Big tracks).
VIEW = {"map": "gps", "zoom": 8, "bbox": "6.999,49.999,7.001,50.005", "bbox_zoom": 18}

# A 2000-point drive north with a 20 m zigzag every 100 points: about 2.2 km.
ZIGZAG = 2e-4


@pytest.fixture
def zigzag_leg(client, leg):
    signed_in(client, "vera", "viewer")
    master = start_auto(leg)
    fixes = [
        pose_writes.GpsFix(7.0 + (ZIGZAG if (i // 100) % 2 else 0.0), 50.0 + i * 1e-5)
        for i in range(2000)
    ]
    pose_writes.store_poses(master, fixes)
    return leg, master


def tracks(client, leg, **params):
    response = client.get(f"/gui/api/legs/{leg.pk}/tracks/", params)
    assert response.status_code == 200, response.content
    return response.json()


def test_zoomed_out_the_track_is_thin_and_keeps_its_ends(client, zigzag_leg):
    leg, master = zigzag_leg
    full = tracks(client, leg)["segments"][str(master.pk)]
    far = tracks(client, leg, zoom=8)["segments"][str(master.pk)]
    assert len(full["gps"]) == 2000
    # At zoom 8 a pixel is 600 m: the 20 m zigzag vanishes, the ends stay.
    assert len(far["gps"]) < 10
    assert far["gps"][0] == full["gps"][0] and far["gps"][-1] == full["gps"][-1]
    assert far["distance_m"] == full["distance_m"] > 2000


def test_zoomed_in_every_visible_corner_stays(client, zigzag_leg):
    leg, master = zigzag_leg
    near = tracks(client, leg, zoom=18)
    assert near["tolerance_deg"] == zoom_tolerance(18) < ZIGZAG / 10
    points = near["segments"][str(master.pk)]["gps"]
    # Two corners per step of the zigzag (20 steps), and the two ends.
    assert 40 <= len(points) < 100
    assert {round(lon, 7) for _, lon in points} == {7.0, 7.0 + ZIGZAG}


def test_tracks_are_gzipped_for_a_browser_that_takes_gzip(client, zigzag_leg):
    leg, _ = zigzag_leg
    plain = client.get(f"/gui/api/legs/{leg.pk}/tracks/")
    packed = client.get(f"/gui/api/legs/{leg.pk}/tracks/", HTTP_ACCEPT_ENCODING="gzip")
    assert packed["Content-Encoding"] == "gzip"
    assert len(packed.content) < len(plain.content) / 3
    assert json.loads(gzip.decompress(packed.content)) == plain.json()


@pytest.mark.parametrize("zoom", ["-1", "25", "x", "1.5"])
def test_a_wrong_zoom_is_refused_with_a_field_message(client, zigzag_leg, zoom):
    leg, _ = zigzag_leg
    response = client.get(f"/gui/api/legs/{leg.pk}/tracks/", {"zoom": zoom})
    assert response.status_code == 400
    assert "zoom" in response.json()["errors"]


def test_fit_thins_for_the_zoom_that_shows_the_whole_leg_and_says_which(client, zigzag_leg):
    leg, master = zigzag_leg
    # 2.2 km north in 700 x 500 pixels: zoom 14 (about 10 m a pixel), the 20 m zigzag stays.
    body = tracks(client, leg, fit="700,500")
    assert body["zoom"] == 14
    assert body["local_zoom"] is None  # no local track
    assert body["tolerance_deg"] == zoom_tolerance(14)
    points = body["segments"][str(master.pk)]["gps"]
    assert 40 <= len(points) < 100


def test_the_area_in_view_comes_in_detail_and_the_rest_thinned(client, zigzag_leg):
    leg, master = zigzag_leg
    # The southern quarter in view at zoom 18, the rest at zoom 8.
    box = "6.999,49.999,7.001,50.005"
    body = tracks(client, leg, map="gps", zoom=8, bbox=box, bbox_zoom=18)
    assert body["map"] == "gps" and body["bbox_zoom"] == 18
    points = body["segments"][str(master.pk)]
    in_view = [p for p in points if p[0] <= 50.005]
    outside = [p for p in points if p[0] > 50.005]
    # Five zigzag steps in view keep their corners; outside, a few points only.
    assert len(in_view) >= 10
    assert {round(lon, 7) for _, lon in in_view} == {7.0, 7.0 + ZIGZAG}
    assert len(outside) < 5
    assert points[-1] == [50.0 + 1999 * 1e-5, 7.0 + ZIGZAG]


@pytest.mark.parametrize(
    "params, field",
    [
        ({"fit": "0,500"}, "fit"),
        ({"fit": "700"}, "fit"),
        ({"map": "gps", "bbox": "7,50,6,51", "bbox_zoom": 18}, "bbox"),
        ({"map": "gps", "bbox": "7,50,x,51", "bbox_zoom": 18}, "bbox"),
        ({"map": "gps", "bbox_zoom": 18}, "bbox"),
        ({"map": "gps", "bbox": "7,50,8,51", "bbox_zoom": -2}, "bbox_zoom"),
        ({"map": "moon", "bbox": "7,50,8,51", "bbox_zoom": 2}, "map"),
    ],
)
def test_a_wrong_view_is_refused_with_a_field_message(client, zigzag_leg, params, field):
    leg, _ = zigzag_leg
    response = client.get(f"/gui/api/legs/{leg.pk}/tracks/", params)
    assert response.status_code == 400
    assert field in response.json()["errors"]


def test_the_local_map_zooms_below_zero(client, zigzag_leg):
    leg, master = zigzag_leg
    pose_writes.store_local_poses(
        master, [pose_writes.MapPose(float(i), 0.0, "map") for i in range(50)]
    )
    body = tracks(client, leg, map="local", zoom=-3, bbox="0,-1,10,1", bbox_zoom=-1)
    # A straight line keeps its ends and the point past the view where its detail ends.
    assert body["segments"][str(master.pk)] == [[0.0, 0.0], [12.0, 0.0], [49.0, 0.0]]


def _queries_for_tracks(client, leg, **params):
    with CaptureQueriesContext(connection) as queries:
        tracks(client, leg, **params)
    return len(queries)


@pytest.mark.parametrize("params", [{"fit": "800,600"}, VIEW])
def test_reading_the_tracks_takes_as_many_queries_for_many_segments_as_for_one(
    client, zigzag_leg, params
):
    leg, master = zigzag_leg
    pose_writes.store_local_poses(master, [pose_writes.MapPose(i, 0.0, "map") for i in range(20)])
    # A process's first request looks up what it keeps for the next ones (the
    # account's language, the site's caches): not counted.
    tracks(client, leg, **params)
    forget_cached_tracks()
    one = [_queries_for_tracks(client, leg, **params), _queries_for_tracks(client, leg, **params)]
    for k in range(5):
        master = segments.report_mode(leg, "ito" if k % 2 == 0 else "auto").master
        pose_writes.store_poses(
            master, [pose_writes.GpsFix(7.01 + k * 1e-3, 50.0 + i * 1e-5) for i in range(20)]
        )
        pose_writes.store_local_poses(
            master, [pose_writes.MapPose(k + i, 0.0, "map") for i in range(20)]
        )
    forget_cached_tracks()
    # The first read of the tracks, then one that finds them kept.
    assert [
        _queries_for_tracks(client, leg, **params),
        _queries_for_tracks(client, leg, **params),
    ] == one


def test_a_pose_that_arrives_late_for_a_closed_segment_is_in_the_next_read(client, zigzag_leg):
    leg, master = zigzag_leg
    segments.report_mode(leg, "ito")
    before = tracks(client, leg)["segments"][str(master.pk)]
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.3, 50.0005, robot_stamp=None)])
    after = tracks(client, leg)["segments"][str(master.pk)]
    assert len(after["gps"]) == len(before["gps"]) + 1 == 2001
    assert after["gps"][-1] == [50.0005, 7.3]
    assert after["distance_m"] > before["distance_m"] + 20000


def test_each_master_says_where_it_started_for_its_take_over_circle(client, zigzag_leg):
    leg, master = zigzag_leg
    ito = segments.report_mode(
        leg, "ito", gps=segments.GpsPosition(7.25, 50.5), local=segments.LocalPosition(3.0, -4.0)
    ).master
    body = tracks(client, leg, fit="800,600")["segments"]
    assert body[str(ito.pk)]["start"] == [50.5, 7.25]
    assert body[str(ito.pk)]["start_local"] == [3.0, -4.0]
    assert body[str(master.pk)]["start"] is None and body[str(master.pk)]["start_local"] is None


def test_a_moved_start_position_changes_the_distance_in_the_next_read(client, zigzag_leg):
    leg, master = zigzag_leg
    before = tracks(client, leg)["segments"][str(master.pk)]["distance_m"]
    # An operator corrects where the segment started: 0.01 degrees (about 1.1 km) south.
    master.start_position = Point(7.0, 49.99, srid=4326)
    master.save(update_fields=["start_position"])
    after = tracks(client, leg)["segments"][str(master.pk)]["distance_m"]
    assert after > before + 1000
