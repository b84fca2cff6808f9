"""The cockpit's distances read: each master segment's driven distance, the same
figure as the tracks read, without its points and in a fixed number of queries."""

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events.services import segments
from telemetry.services import pose_writes
from tests.support.accounts import signed_in
from tests.support.caches import forget_cached_tracks
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db


def _drive(master, east, n=50):
    pose_writes.store_poses(master, [pose_writes.GpsFix(east, 50.0 + i * 1e-5) for i in range(n)])


def _get(client, leg, what):
    response = client.get(f"/gui/api/legs/{leg.pk}/{what}/")
    assert response.status_code == 200, response.content
    return response.json()


def test_each_segment_has_the_distance_the_tracks_read_gives_and_no_points(client, leg):
    signed_in(client, "vera", "viewer")
    first = start_auto(leg)
    _drive(first, 7.0, 2000)
    second = segments.report_mode(leg, "ito").master
    _drive(second, 7.01)
    answer = _get(client, leg, "distances")
    assert set(answer) == {"leg", "distances"} and answer["leg"] == leg.pk
    tracks = _get(client, leg, "tracks")["segments"]
    assert answer["distances"] == {k: t["distance_m"] for k, t in tracks.items()}
    # 2000 fixes 1.1 m apart: about 2.2 km.
    assert 2100 < answer["distances"][str(first.pk)] < 2300


def test_a_late_pose_changes_the_distance_in_the_next_read(client, leg):
    signed_in(client, "vera", "viewer")
    master = start_auto(leg)
    _drive(master, 7.0)
    before = _get(client, leg, "distances")["distances"][str(master.pk)]
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.0, 50.01, robot_stamp=None)])
    after = _get(client, leg, "distances")["distances"][str(master.pk)]
    assert after > before + 500


def _queries(client, leg):
    with CaptureQueriesContext(connection) as queries:
        _get(client, leg, "distances")
    return len(queries)


def test_the_read_does_not_grow_with_segments(client, leg):
    signed_in(client, "vera", "viewer")
    _drive(start_auto(leg), 7.0)
    _get(client, leg, "distances")
    forget_cached_tracks()
    one = _queries(client, leg)
    for k in range(6):
        _drive(segments.report_mode(leg, "ito" if k % 2 == 0 else "auto").master, 7.01 + k * 1e-3)
    forget_cached_tracks()
    assert _queries(client, leg) == one


def test_a_signed_out_browser_gets_no_distances(client, leg):
    assert client.get(f"/gui/api/legs/{leg.pk}/distances/").status_code in (401, 403)
