"""The production server's route for single poses answers as the API view does.

Requests go through the real ASGI application (ftt_site.asgi); the view's own
answers come from Django's test client.  The database work of the ASGI
application runs in other threads, so these tests commit (transaction=True).
"""

import asyncio
import json
import uuid

import httpx
import psycopg
import pytest
from django.core.signals import request_started
from django.db import transaction
from django.db.models.signals import post_save
from prometheus_client.parser import text_string_to_metric_families
from rest_framework.throttling import SimpleRateThrottle

from common.sql import conninfo
from events.models import Announcement, SegmentType
from events.services import segments
from ftt_site.asgi import application
from ftt_site.inbound.pose_route import PATH
from live.wakeup import CHANNEL
from telemetry.models import Pose
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db(transaction=True)

# Answered per request, not by the route: the server's clock and the length.
_PER_ANSWER = {"date", "server", "content-length"}


@pytest.fixture
def master(leg):
    return start_auto(leg)


@pytest.fixture
def django_requests(master, api_client):
    """How many requests Django's own handler took (the route takes none once it
    knows the headers of Django's answer, from the first pose of the process)."""
    post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, api_client("operator").token)
    seen = []

    def count(**kwargs):
        seen.append(kwargs)

    request_started.connect(count)
    yield seen
    request_started.disconnect(count)


def post_asgi(body, token=None, headers=None):
    """POST /api/poses/ through the ASGI application; (status, headers, json)."""

    async def send():
        sent = {"Content-Type": "application/json", **(headers or {})}
        if token:
            sent["Authorization"] = f"Token {token}"
        transport = httpx.ASGITransport(app=application)
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as client:
            return await client.post(PATH, content=json.dumps(body), headers=sent)

    response = asyncio.run(send())
    return response.status_code, response.headers, response.json()


def _headers(headers) -> dict:
    # The policy's directives come in set order; compare them as a set.
    found = {k.lower(): v for k, v in headers.items() if k.lower() not in _PER_ANSWER}
    if "content-security-policy" in found:
        found["content-security-policy"] = set(found["content-security-policy"].split("; "))
    return found


def _stored(uid):
    pose = Pose.objects.get(uid=uid)
    return {
        "segment": pose.segment_id,
        "point": (pose.point.x, pose.point.y, pose.point.srid),
        "altitude": pose.altitude,
        "fix_status": pose.fix_status,
        "horizontal_accuracy": pose.horizontal_accuracy,
        "pose_source": pose.pose_source_id,
        "robot_stamp": pose.robot_stamp,
    }


def test_a_pose_is_stored_and_answered_as_the_view_does(
    api_client, master, django_requests, media_root
):
    client = api_client("operator")
    child = segments.report_mode(master.leg, SegmentType.ITO).master
    sent = {
        "segment": child.pk,
        "longitude": 7.1,
        "latitude": 50.7,
        "altitude": 62.5,
        "fix_status": 2,
        "horizontal_accuracy": 0.02,
        "robot_stamp": "2026-05-04T10:00:00.25+02:00",
    }
    lean_uid, view_uid = uuid.uuid4(), uuid.uuid4()
    feed_before = Announcement.objects.count()

    status, headers, lean = post_asgi({**sent, "uid": str(lean_uid)}, client.token)
    assert django_requests == []  # answered by the route alone
    view = client.post(PATH, {**sent, "uid": str(view_uid)}, format="json")

    assert (status, view.status_code) == (201, 201)
    different = {"id", "uid", "received"}
    assert {k: v for k, v in lean.items() if k not in different} == {
        k: v for k, v in view.json().items() if k not in different
    }
    assert lean["uid"] == str(lean_uid) and lean["robot_stamp"] == "2026-05-04T08:00:00.250000Z"
    assert _stored(lean_uid) == _stored(view_uid)
    assert _headers(headers) == _headers(view.headers)
    # One feed row each, naming the same segment and point.
    feed = list(Announcement.objects.order_by("pk")[feed_before:])
    assert [(a.kind, a.payload) for a in feed[:1]] == [(a.kind, a.payload) for a in feed[1:]]


def test_a_retried_uid_is_stored_once_and_answered_with_the_first_row(
    api_client, master, django_requests
):
    token = api_client("operator").token
    body = {"uid": str(uuid.uuid4()), "segment": master.pk, "longitude": 8, "latitude": 50}

    first = post_asgi(body, token)
    again = post_asgi(body, token)

    assert django_requests == []
    assert (first[0], again[0]) == (201, 200)
    assert again[2] == first[2]
    assert Pose.objects.filter(uid=body["uid"]).count() == 1


def test_a_robot_posts_to_its_own_vehicle_the_lean_way(
    robot_client, vehicle, master, django_requests
):
    token = robot_client(vehicle).token

    status, _, answer = post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, token)

    assert status == 201 and django_requests == []
    assert Pose.objects.filter(uid=answer["uid"], segment=master).exists()


def _refusals(master, other_leg):
    foreign = start_auto(other_leg)
    good = {"segment": master.pk, "longitude": 8, "latitude": 50}
    return {
        "bad field": ("operator", {**good, "latitude": 95}),
        "text for a number": ("operator", {**good, "longitude": "east"}),
        "unknown segment": ("operator", {**good, "segment": 10**9}),
        "unknown pose source": ("operator", {**good, "pose_source": 10**9}),
        "not an object": ("operator", [good]),
        "viewer": ("viewer", good),
        "no role": (None, good),
        "no token": ("anonymous", good),
        "unknown token": ("unknown", good),
        "robot, other vehicle": ("robot", {**good, "segment": foreign.pk}),
        "JSON with NaN": ("operator", {**good, "altitude": float("nan")}),
    }


REFUSALS = [
    "bad field",
    "text for a number",
    "unknown segment",
    "unknown pose source",
    "not an object",
    "viewer",
    "no role",
    "no token",
    "unknown token",
    "robot, other vehicle",
    "JSON with NaN",
]


@pytest.mark.parametrize("case", REFUSALS)
def test_what_the_route_cannot_answer_gets_the_views_answer(
    case, api_client, robot_client, vehicle, master, other_leg
):
    role, body = _refusals(master, other_leg)[case]
    if role == "robot":
        client = robot_client(vehicle)
        token = client.token
    elif role in ("anonymous", "unknown"):
        client = api_client(anonymous=True)
        token = None if role == "anonymous" else "0" * 40
        if token:
            client.credentials(HTTP_AUTHORIZATION=f"Token {token}")
    else:
        client = api_client(role)
        token = client.token
    before = Pose.objects.count()

    status, headers, answer = post_asgi(body, token)
    view = client.post(PATH, json.dumps(body), content_type="application/json")

    assert status == view.status_code and status >= 400
    assert answer == view.json()
    assert _headers(headers) == _headers(view.headers)
    assert Pose.objects.count() == before


def test_a_browsers_cross_origin_post_gets_djangos_cors_headers(
    api_client, master, settings, django_requests
):
    settings.CORS_ALLOWED_ORIGINS = ["https://gui.example"]
    client = api_client("operator")
    body = {"segment": master.pk, "longitude": 8, "latitude": 50}
    origin = {"Origin": "https://gui.example"}

    status, headers, _ = post_asgi(body, client.token, origin)
    view = client.post(PATH, body, format="json", HTTP_ORIGIN=origin["Origin"])

    assert len(django_requests) == 2  # the route left it to Django
    assert (status, view.status_code) == (201, 201)
    assert headers["access-control-allow-origin"] == "https://gui.example"
    assert _headers(headers) == _headers(view.headers)


def test_the_lean_way_counts_against_the_request_rate(api_client, master, monkeypatch):
    monkeypatch.setattr(SimpleRateThrottle, "THROTTLE_RATES", {"anon": "2/min", "user": "2/min"})
    token = api_client("operator").token
    body = {"segment": master.pk, "longitude": 8, "latitude": 50}

    answers = [post_asgi(body, token) for _ in range(3)]

    assert [status for status, _, _ in answers] == [201, 201, 429]
    assert "retry-after" in answers[2][1]
    assert Pose.objects.filter(segment=master).count() == 2


def test_one_throttle_count_per_request(api_client, master, monkeypatch):
    """Issue 31, finding 9: with 5 requests a minute, the 6th is refused, whether
    the route or Django answered the ones before it (a body the route leaves to
    Django, a refused segment it answers itself)."""
    token = api_client("operator").token
    post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, token)  # headers known
    monkeypatch.setattr(SimpleRateThrottle, "THROTTLE_RATES", {"anon": "5/min", "user": "5/min"})
    good = {"segment": master.pk, "longitude": 8, "latitude": 50}
    bodies = [good, {**good, "segment": str(master.pk)}, {**good, "segment": 10**9}, good, good]

    statuses = [post_asgi(body, token)[0] for body in bodies]

    assert statuses == [201, 201, 400, 201, 429]
    assert Pose.objects.filter(segment=master).count() == 1 + 3


def test_a_failure_after_the_commit_does_not_store_the_pose_twice(api_client, master):
    """Something that runs after the pose's commit fails: the request is not
    sent on to Django, which would store a pose sent without a uid again."""
    token = api_client("operator").token
    post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, token)  # headers known
    before = Pose.objects.filter(segment=master).count()

    def fail():
        raise RuntimeError("a bug after the commit")

    def after_commit_fails(**kwargs):
        transaction.on_commit(fail)

    post_save.connect(after_commit_fails, sender=Announcement)
    try:
        status, _, _ = post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, token)
    finally:
        post_save.disconnect(after_commit_fails, sender=Announcement)

    assert Pose.objects.filter(segment=master).count() == before + 1
    assert status == 500


@pytest.mark.postgis_only
def test_a_pose_the_lean_way_wakes_the_live_readers_at_once(api_client, master):
    token = api_client("operator").token
    with psycopg.connect(conninfo(), autocommit=True) as listener:
        listener.execute(f"LISTEN {CHANNEL}")
        status, _, _ = post_asgi({"segment": master.pk, "longitude": 8, "latitude": 50}, token)
        heard = list(listener.notifies(timeout=1.0, stop_after=1))

    assert status == 201
    assert [note.channel for note in heard] == [CHANNEL]


def _pose_figures(client) -> tuple[float, float, float]:
    """(POST /api/poses/ answered 201, latency observations, requests counted) of /metrics."""
    stored = latencies = requests = 0.0
    for family in text_string_to_metric_families(client.get("/metrics").content.decode()):
        for sample in family.samples:
            labels = sample.labels
            if labels.get("view") != "pose-list" or labels.get("method") != "POST":
                continue
            if sample.name == "django_http_responses_total_by_status_view_method_total":
                stored += sample.value if labels["status"] == "201" else 0
            elif sample.name == "django_http_requests_latency_seconds_by_view_method_count":
                latencies += sample.value
            elif sample.name == "django_http_requests_total_by_view_transport_method_total":
                requests += sample.value
    return stored, latencies, requests


def test_single_poses_the_lean_way_are_in_the_request_metrics(
    api_client, master, django_requests, client, settings
):
    settings.FTT_METRICS_TOKEN = "scraper"
    client.defaults["HTTP_AUTHORIZATION"] = "Bearer scraper"
    before = _pose_figures(client)
    token = api_client("operator").token
    seen = len(django_requests)
    for n in range(3):
        body = {"segment": master.pk, "longitude": 8 + n / 1000, "latitude": 50}
        assert post_asgi(body, token)[0] == 201
    assert len(django_requests) == seen  # the route answered them
    assert _pose_figures(client) == tuple(figure + 3 for figure in before)
