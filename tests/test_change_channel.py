"""The history's channel is the route a write took, never a header the client sent."""

import json

from django.test import Client, RequestFactory

from events.models import Segment, TestEvent, Vehicle
from events.services import logs
from events.services.robots import ensure_robot_account
from ftt_site.inbound.change_origin import channel_of


def test_a_write_of_the_original_robots_api_is_recorded_as_its_own_channel(db):
    vehicle = Vehicle.objects.create(key="husky", short_description="Husky")
    event = logs.create_test_event(location="Wachtberg")
    leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
    token = ensure_robot_account("husky-robot", [vehicle]).token
    body = {"leg_id": "Current Leg", "segment_type_id": 2, "ito_reason_id": 11}
    answer = Client().post(
        f"/legacy/{token}/segment", json.dumps(body), content_type="application/json"
    )
    assert answer.status_code == 200, answer.content
    master = Segment.objects.get(leg=leg, parent__isnull=True)
    assert [e.history_channel for e in master.history.all()] == ["legacy"]


def test_an_authorization_header_does_not_make_a_page_call_an_api_write():
    factory = RequestFactory()
    page_call = factory.post("/gui/api/legs/1/quick-reason/", HTTP_AUTHORIZATION="Token x")
    assert channel_of(page_call) == "gui"
    assert channel_of(factory.post("/api/segments/")) == "api"
    assert channel_of(factory.post("/admin/events/segment/1/change/")) == "admin"


def test_a_session_write_with_an_authorization_header_stays_the_gui_s(role_user):
    operator = role_user("operator")
    page = Client()
    page.force_login(operator)
    written = {}
    for name, client, headers in (
        ("session", page, {"HTTP_AUTHORIZATION": "Basic b3R0bzpwdw=="}),
        ("token", Client(), {"HTTP_AUTHORIZATION": f"Token {operator.auth_token.key}"}),
    ):
        answer = client.post(
            "/api/test-events/",
            json.dumps({"location": name}),
            content_type="application/json",
            **headers,
        )
        assert answer.status_code == 201, answer.content
        event = TestEvent.objects.get(pk=answer.json()["id"])
        written[name] = [e.history_channel for e in event.history.all()]
    assert written == {"session": ["gui"], "token": ["api"]}
