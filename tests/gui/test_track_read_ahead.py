"""The cockpit page reads its leg's tracks ahead of the map's request."""

import threading

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext

from telemetry.services import pose_writes
from tests.support.accounts import signed_in
from tests.support.caches import forget_cached_tracks
from tests.support.modes import start_auto

# Committed for real, as a server runs it: the read ahead has a connection of its own.
pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture
def driven_leg(client, leg):
    signed_in(client, "vera", "viewer")
    master = start_auto(leg)
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.0, 50.0 + i * 1e-5) for i in range(300)])
    pose_writes.store_local_poses(master, [pose_writes.MapPose(i, 0.0, "map") for i in range(300)])
    return leg, master


def _open_cockpit(client, leg):
    shift = leg.shift
    page = client.get(f"/?event={shift.test_event_id}&shift={shift.pk}&leg={leg.pk}")
    assert page.status_code == 200
    for thread in threading.enumerate():
        if thread.name == "tracks-read-ahead":
            thread.join(30)


def _tracks(client, leg):
    with CaptureQueriesContext(connection) as queries:
        response = client.get(f"/gui/api/legs/{leg.pk}/tracks/", {"fit": "800,600"})
    assert response.status_code == 200, response.content
    return response.json(), len(queries)


def test_after_the_page_the_tracks_answer_reads_no_track(client, driven_leg):
    leg, master = driven_leg
    forget_cached_tracks()
    cold, cold_queries = _tracks(client, leg)
    _, warm_queries = _tracks(client, leg)
    assert warm_queries < cold_queries

    forget_cached_tracks()
    _open_cockpit(client, leg)
    ahead, queries = _tracks(client, leg)
    # The same answer as a read of its own, with the queries of an answer whose tracks were kept.
    assert ahead == cold
    assert queries == warm_queries
    assert len(ahead["segments"][str(master.pk)]["local"]) >= 2


def test_a_pose_stored_after_the_read_ahead_is_in_the_answer(client, driven_leg):
    leg, master = driven_leg
    forget_cached_tracks()
    _open_cockpit(client, leg)
    # The robot drives on after the page opened, 3 km north.
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.0, 50.03)])
    body, _ = _tracks(client, leg)
    track = body["segments"][str(master.pk)]
    assert track["gps"][-1] == [50.03, 7.0]
    assert track["distance_m"] > 3000
