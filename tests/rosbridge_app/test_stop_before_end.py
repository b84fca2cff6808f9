"""Ending a level stops logging into it first, whoever ends it.

The rule lives in rosbridge_app.services.collectors.stop_logging_into, called
from the closing services; each caller (REST API, GUI, Django admin, a
service call) is tried here and must leave a stop order for the collector.
"""

import pytest
from django.urls import reverse
from django.utils import timezone

from events.models import Leg
from events.services import logs
from rosbridge_app.models import Collector, CollectorCommand
from tests.support.accounts import staff_user

pytestmark = pytest.mark.django_db


@pytest.fixture
def logging_collector(leg):
    return Collector.objects.create(
        name="robot/husky",
        vehicle=leg.shift.vehicle,
        logging=True,
        leg=leg,
        last_seen=timezone.now(),
    )


def stop_orders(collector):
    return list(
        CollectorCommand.objects.filter(
            collector=collector, kind=CollectorCommand.Kind.STOP_LOGGING
        ).values_list("done", flat=True)
    )


@pytest.mark.parametrize("level", ["legs", "shifts", "test-events"])
def test_ending_through_the_api_stops_logging_first(api_client, leg, logging_collector, level):
    target = {"legs": leg, "shifts": leg.shift, "test-events": leg.shift.test_event}[level]
    response = api_client("operator").post(f"/api/{level}/{target.pk}/close/", {}, format="json")
    assert response.status_code == 200, response.content
    assert stop_orders(logging_collector) == [None]
    leg.refresh_from_db()
    assert leg.end is not None


def test_the_gui_ends_with_one_request_while_logging(client, role_user, leg, logging_collector):
    """The GUI's End button is one POST: no stop request from the page first."""
    client.force_login(role_user("operator"))
    response = client.post(f"/api/legs/{leg.pk}/close/", {}, content_type="application/json")
    assert response.status_code == 200, response.content
    assert stop_orders(logging_collector) == [None]


def test_ending_from_django_admin_stops_logging_first(client, leg, logging_collector):
    client.force_login(staff_user("administrator"))
    response = client.post(
        reverse("admin:events_shift_changelist"),
        {"action": "close_selected", "_selected_action": [leg.shift.pk]},
        follow=True,
    )
    assert response.status_code == 200
    assert stop_orders(logging_collector) == [None]
    assert Leg.objects.get(pk=leg.pk).end is not None


def test_a_collector_logging_elsewhere_is_left_alone(leg, logging_collector, other_vehicle):
    other_shift = logs.create_shift(test_event=leg.shift.test_event, vehicle=other_vehicle)
    other_leg = logs.create_leg(shift=other_shift)
    logs.close_leg(other_leg)
    assert stop_orders(logging_collector) == []


def test_a_second_end_does_not_pile_up_stop_orders(leg, logging_collector):
    logs.close_leg(leg)
    logs.close_shift(leg.shift)
    assert stop_orders(logging_collector) == [None]


def test_a_new_leg_in_the_same_shift_keeps_logging(leg, logging_collector):
    """The collector follows the vehicle's open leg; starting the next leg is no end."""
    logs.create_leg(shift=leg.shift)
    assert stop_orders(logging_collector) == []
