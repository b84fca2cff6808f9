"""Writes of the collector link (see rosbridge_app.models and docs/collector.md).

The GUI side issues commands; the collector side registers, beats, takes and
finishes commands and announces what it stored.
"""

from datetime import timedelta

from django.db import transaction
from django.utils import timezone

from events.errors import RuleViolation
from rosbridge_app.models import Announcement, Collector, CollectorCommand

ANNOUNCEMENT_RETENTION = timedelta(hours=1)
# A command nobody took within this time is answered as failed, so the GUI
# never waits forever for an offline collector.
COMMAND_EXPIRY = timedelta(seconds=30)


# --- GUI side ---------------------------------------------------------------------------


@transaction.atomic
def issue_command(
    collector: Collector, kind: str, arguments: dict | None = None, user=None
) -> CollectorCommand:
    if kind not in CollectorCommand.Kind.values:
        raise RuleViolation({"kind": [f"Unknown command '{kind}'."]})
    arguments = arguments or {}
    if kind == CollectorCommand.Kind.SET_PARAMETERS:
        values = arguments.get("parameters")
        if not isinstance(values, dict) or not values:
            raise RuleViolation(
                {"parameters": ["Give the parameters to set as a non-empty object."]}
            )
    return CollectorCommand.objects.create(
        collector=collector, kind=kind, arguments=arguments, issued_by=user
    )


# --- collector side ---------------------------------------------------------------------


# A change in one of these is announced, so open browsers redraw the collector panel.
_ANNOUNCED = ("logging", "leg_id", "state", "stopped", "vehicle_id")


@transaction.atomic
def heartbeat(name: str, **fields) -> Collector:
    """Register or refresh a collector; ``fields`` are Collector columns."""
    fields["last_seen"] = timezone.now()
    before = Collector.objects.filter(name=name).values(*_ANNOUNCED).first()
    collector, _ = Collector.objects.update_or_create(name=name, defaults=fields)
    after = {key: getattr(collector, key) for key in _ANNOUNCED}
    if before != after:
        announce(
            Announcement.Kind.COLLECTOR,
            collector,
            collector.leg,
            {"collector": collector.pk, "logging": collector.logging, "online": True},
        )
    return collector


@transaction.atomic
def take_commands(collector: Collector) -> list[CollectorCommand]:
    """The collector's open commands, oldest first, marked as taken."""
    now = timezone.now()
    stale = CollectorCommand.objects.filter(
        collector=collector,
        done__isnull=True,
        taken__isnull=True,
        issued__lt=now - COMMAND_EXPIRY,
    )
    for command in stale:
        _finish(command, False, "The collector did not take the command in time.", {})
    # Taken by an earlier run of this collector that died before answering: the
    # person who issued it must not wait for an answer that never comes.
    orphaned = CollectorCommand.objects.filter(
        collector=collector,
        done__isnull=True,
        taken__lt=now - COMMAND_EXPIRY,
    )
    for command in orphaned:
        _finish(
            command,
            False,
            "The collector stopped before carrying this out; check its state and try again.",
            {},
        )
    todo = list(
        CollectorCommand.objects.select_for_update()
        .filter(collector=collector, done__isnull=True, taken__isnull=True)
        .order_by("id")
    )
    for command in todo:
        command.taken = now
        command.save(update_fields=["taken"])
    return todo


@transaction.atomic
def finish_command(
    command: CollectorCommand, success: bool, message: str, result: dict | None = None
) -> CollectorCommand:
    return _finish(command, success, message, result or {})


def _finish(command, success, message, result):
    command.done = timezone.now()
    command.success = success
    command.message = message
    command.result = result
    command.save(update_fields=["done", "success", "message", "result"])
    Announcement.objects.create(
        kind=Announcement.Kind.COMMAND,
        collector_id=command.collector_id,
        payload={
            "command": command.pk,
            "kind": command.kind,
            "success": success,
            "message": message,
        },
    )
    return command


def announce(kind: str, collector: Collector | None, leg=None, payload: dict | None = None):
    """Add to the outbox; call inside the transaction that stored the data."""
    return Announcement.objects.create(
        kind=kind, collector=collector, leg=leg, payload=payload or {}
    )


def prune_announcements() -> int:
    cutoff = timezone.now() - ANNOUNCEMENT_RETENTION
    return Announcement.objects.filter(created__lt=cutoff).delete()[0]


@transaction.atomic
def mark_stopped(collector: Collector) -> None:
    Collector.objects.filter(pk=collector.pk).update(
        stopped=timezone.now(), logging=False, last_seen=timezone.now()
    )
    announce(Announcement.Kind.COLLECTOR, collector, None, {"online": False})
