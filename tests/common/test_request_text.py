"""A lone surrogate in any JSON text is a 400 with the same message, never a 500
(issue 31, finding 7): one parser check (common.text) for the API and the
production server's lean pose route."""

import asyncio
import json
import uuid

import httpx
import pytest

from common import roles
from events.models import SegmentType
from events.services import segments
from ftt_site.asgi import application
from telemetry.models import Pose

LONE = "\ud800"


def send(client, method, url, body):
    # Escaped as a client sends it (DRF's test renderer would not encode it).
    return getattr(client, method)(url, json.dumps(body), content_type="application/json")


def assert_refused(response):
    assert response.status_code == 400, response.content
    assert "lone UTF-16 surrogate" in response.json()["detail"]


def test_a_test_events_time_zone(api_client, test_event):
    operator = api_client(roles.OPERATOR)
    assert_refused(
        send(operator, "patch", f"/api/test-events/{test_event.pk}/", {"time_zone": LONE})
    )


def test_a_legs_mode(api_client, leg):
    assert_refused(
        send(api_client(roles.OPERATOR), "post", f"/api/legs/{leg.pk}/mode/", {"mode": LONE})
    )


def test_a_key_and_a_pair_that_is_one_character(api_client, leg):
    operator = api_client(roles.OPERATOR)
    assert_refused(send(operator, "post", f"/api/legs/{leg.pk}/mode/", {LONE: "auto"}))
    # An escaped pair is a real character (here an emoji): that is not refused for it.
    response = send(operator, "post", f"/api/legs/{leg.pk}/mode/", {"mode": "\U0001f600"})
    assert "surrogate" not in response.content.decode()


@pytest.mark.django_db(transaction=True)
def test_a_robots_single_pose_through_the_production_route(robot_client, vehicle, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    robot = robot_client(vehicle)
    token = robot.token
    pose = {"segment": master.pk, "longitude": 7.1, "latitude": 50.2, "uid": str(uuid.uuid4())}

    async def post():
        transport = httpx.ASGITransport(app=application)
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as client:
            return await client.post(
                "/api/poses/",
                content=json.dumps({**pose, "fix_status": LONE}),
                headers={"Content-Type": "application/json", "Authorization": f"Token {token}"},
            )

    assert_refused(asyncio.run(post()))
    assert not Pose.objects.exists()
