"""Before the cockpit ends what robots log into, it asks the server what that
would end (``/gui/api/ending/``) and names it: the vehicles whose logging
stops, the shifts, the legs and the open take-overs.  Asking writes nothing;
the robot panel says when a collector logs into a leg that has ended."""

import pytest

from events.models import Leg
from events.services import logs, segments
from rosbridge_app.services import collectors

pytestmark = pytest.mark.django_db


def ask(client, action, pk):
    return client.get("/gui/api/ending/", {"action": action, "id": pk})


def test_ending_a_test_event_names_both_robots_their_legs_and_the_open_take_over(
    api_client, test_event, leg, other_leg
):
    collectors.heartbeat("field-1", vehicle=leg.shift.vehicle, logging=True, leg=leg)
    collectors.heartbeat("field-2", vehicle=other_leg.shift.vehicle, logging=True, leg=other_leg)
    segments.report_mode(other_leg, "ito")
    answer = ask(api_client("viewer"), "end-event", test_event.pk)
    assert answer.status_code == 200, answer.content
    body = answer.json()
    assert sorted(v["name"] for v in body["vehicles"]) == ["Husky A200", "Jackal"]
    assert sorted(s["name"] for s in body["shifts"]) == ["Husky A200 · Shift 1", "Jackal · Shift 2"]
    assert sorted(g["name"] for g in body["legs"]) == [
        "Husky A200 · Shift 1 · Leg 1",
        "Jackal · Shift 2 · Leg 1",
    ]
    assert [t["name"] for t in body["take_overs"]] == ["Jackal · Leg 1 · #1.1"]
    assert body["logging_stops"] is True
    # Asking ended nothing.
    assert Leg.objects.filter(end__isnull=True).count() == 2


def test_a_new_leg_names_the_leg_it_ends_and_logging_goes_on(api_client, shift, leg):
    collectors.heartbeat("field-1", vehicle=shift.vehicle, logging=True, leg=leg)
    body = ask(api_client("operator"), "new-leg", shift.pk).json()
    assert [g["name"] for g in body["legs"]] == ["Husky A200 · Shift 1 · Leg 1"]
    assert [v["name"] for v in body["vehicles"]] == ["Husky A200"]
    assert body["take_overs"] == [] and body["logging_stops"] is False


def test_a_closed_leg_ends_nothing_and_wrong_questions_are_told_apart(api_client, leg):
    logs.close_leg(leg)
    client = api_client("viewer")
    body = ask(client, "end-leg", leg.pk).json()
    assert body["legs"] == [] and body["vehicles"] == []
    wrong = ask(client, "end-everything", leg.pk)
    assert wrong.status_code == 400 and "action" in wrong.json()["errors"]
    assert ask(client, "end-leg", 999999).status_code == 404


def test_the_robot_panel_says_a_collector_logs_into_an_ended_leg(api_client, vehicle, leg):
    collectors.heartbeat("field-1", vehicle=vehicle, logging=True, leg=leg)
    client = api_client("viewer")
    status = client.get("/gui/api/collectors/", {"vehicle": vehicle.pk, "leg": leg.pk}).json()
    assert status["stores_nothing"] == ""
    Leg.objects.filter(pk=leg.pk).update(end=leg.start)
    status = client.get("/gui/api/collectors/", {"vehicle": vehicle.pk, "leg": leg.pk}).json()
    assert "Leg 1, which has ended: nothing is stored" in status["stores_nothing"]
