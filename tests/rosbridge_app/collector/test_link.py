"""The database link between the GUI and collectors (rosbridge_app services/selectors)."""

from datetime import timedelta

import pytest
from django.core.exceptions import ValidationError
from django.utils import timezone

from common.errors import RuleViolation
from events.models import Announcement
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.selectors.collectors import collector_status, is_online
from rosbridge_app.services.collectors import (
    finish_command,
    heartbeat,
    issue_command,
    mark_stopped,
    take_commands,
)

pytestmark = pytest.mark.django_db


def test_heartbeat_registers_and_announces_only_changes(vehicle):
    first = heartbeat("robot/husky", vehicle=vehicle, logging=False, state="idle")
    heartbeat("robot/husky", vehicle=vehicle, logging=False, state="idle")
    assert Announcement.objects.filter(kind="collector").count() == 1
    heartbeat("robot/husky", vehicle=vehicle, logging=True, state="logging")
    assert Announcement.objects.filter(kind="collector").count() == 2
    assert Collector.objects.get(pk=first.pk).logging


def test_online_status_and_input_ages(vehicle):
    received = (timezone.now() - timedelta(seconds=4)).isoformat()
    collector = heartbeat(
        "robot/husky", vehicle=vehicle, inputs={"gps_fix": {"count": 3, "last_received": received}}
    )
    status = collector_status(collector)
    assert status["online"] and status["vehicle"] == "husky"
    assert 3.5 < status["inputs"]["gps_fix"]["age"] < 10
    Collector.objects.filter(pk=collector.pk).update(
        last_seen=timezone.now() - timedelta(seconds=10)
    )
    assert not is_online(Collector.objects.get(pk=collector.pk))
    mark_stopped(collector)
    collector = Collector.objects.get(pk=collector.pk)
    assert not is_online(collector) and collector.stopped is not None


def test_commands_are_taken_once_and_answered(vehicle, leg):
    collector = heartbeat("robot/husky", vehicle=vehicle)
    with pytest.raises(RuleViolation):
        issue_command(collector, "self_destruct")
    # A wrong value is the request's fault (400 under its name), not a state's.
    with pytest.raises(ValidationError, match="non-empty object"):
        issue_command(collector, CollectorCommand.Kind.SET_PARAMETERS, {"parameters": {}})
    command = issue_command(collector, CollectorCommand.Kind.START_LOGGING, leg=leg)
    assert take_commands(collector) == [command]
    assert take_commands(collector) == []
    finish_command(command, True, "Logging started.", {"logging": True})
    command.refresh_from_db()
    assert command.success and command.done is not None
    assert Announcement.objects.filter(kind="command").count() == 1


def test_a_poll_that_finds_no_command_is_one_statement(vehicle, django_assert_num_queries):
    # Four polls a second per robot: the idle case must stay one round trip.
    collector = heartbeat("robot/husky", vehicle=vehicle, logging=True)
    done = issue_command(collector, CollectorCommand.Kind.STOP_LOGGING)
    finish_command(done, True, "Logging stopped.")
    with django_assert_num_queries(1):
        assert take_commands(collector) == []


def test_commands_nobody_takes_fail_after_a_while(vehicle):
    collector = heartbeat("robot/husky", vehicle=vehicle, logging=True)
    command = issue_command(collector, CollectorCommand.Kind.STOP_LOGGING)
    CollectorCommand.objects.filter(pk=command.pk).update(
        issued=timezone.now() - timedelta(minutes=5)
    )
    assert take_commands(collector) == []
    command.refresh_from_db()
    assert command.success is False and "in time" in command.message


def test_commands_taken_by_a_collector_that_died_are_answered_on_restart(vehicle):
    collector = heartbeat("robot/husky", vehicle=vehicle)
    command = issue_command(collector, CollectorCommand.Kind.SAVE_PARAMETERS)
    assert take_commands(collector) == [command]
    # The process is killed here; its next run polls again a minute later.
    CollectorCommand.objects.filter(pk=command.pk).update(
        taken=timezone.now() - timedelta(minutes=1)
    )
    assert take_commands(collector) == []
    command.refresh_from_db()
    assert command.done is not None and command.success is False
    assert "stopped before carrying this out" in command.message
    assert Announcement.objects.filter(kind="command", payload__command=command.pk).exists()


def test_a_snapshot_is_asked_for_only_when_the_collector_can_store_one(vehicle):
    on = {"snapshot.enabled": True, "snapshot.before": 20.0, "snapshot.after": 10.0}
    collector = heartbeat("robot/husky", vehicle=vehicle, logging=False, parameters=on)
    with pytest.raises(RuleViolation, match="start logging first"):
        issue_command(collector, CollectorCommand.Kind.SNAPSHOT)
    off = {**on, "snapshot.enabled": False}
    collector = heartbeat("robot/husky", vehicle=vehicle, logging=True, parameters=off)
    with pytest.raises(RuleViolation, match="Snapshots are off"):
        issue_command(collector, CollectorCommand.Kind.SNAPSHOT)
    collector = heartbeat("robot/husky", vehicle=vehicle, logging=True, parameters=on)
    command = issue_command(collector, CollectorCommand.Kind.SNAPSHOT)
    assert take_commands(collector) == [command]
    Collector.objects.filter(pk=collector.pk).update(
        last_seen=timezone.now() - timedelta(seconds=10)
    )
    with pytest.raises(RuleViolation, match="offline"):
        issue_command(Collector.objects.get(pk=collector.pk), CollectorCommand.Kind.SNAPSHOT)
