"""Writes of the collector link (see rosbridge_app.models and docs/collector.md).

The GUI side issues commands; the collector side registers, beats, takes and
finishes commands and announces what it stored.
"""

from datetime import timedelta

from django.core.exceptions import ValidationError
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext

from common.errors import RuleViolation
from events import feed
from events.models import Announcement, Leg
from events.services.logs import closing, count_missed_fixes
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.selectors.control import (
    check_parameter_values,
    logging_control,
    snapshot_control,
)

# A command nobody took within this time is answered as failed, so the GUI
# never waits forever for an offline collector.
COMMAND_EXPIRY = timedelta(seconds=30)


# --- GUI side ---------------------------------------------------------------------------


def issue_command(
    collector: Collector,
    kind: str,
    arguments: dict | None = None,
    user=None,
    leg: Leg | None = None,
) -> CollectorCommand:
    """An order for the collector, refused at once when it cannot apply.

    ``leg`` is the leg the person has selected; starting and stopping follow
    :func:`rosbridge_app.selectors.control.logging_control`, parameter values
    the collector's parameter schema, a snapshot ``snapshot_control``.
    """
    if kind not in CollectorCommand.Kind.values:
        raise RuleViolation({"kind": [(gettext("Unknown command '%(kind)s'.") % {"kind": kind})]})
    arguments = dict(arguments or {})
    if kind == CollectorCommand.Kind.SET_PARAMETERS:
        # Checked before the transaction: parsing a document parameter then
        # holds no write lock (the embedded database takes it at BEGIN).
        values = arguments.get("parameters")
        if not isinstance(values, dict) or not values:
            raise ValidationError(
                {"parameters": [gettext("Give the parameters to set as a non-empty object.")]}
            )
        arguments["parameters"] = check_parameter_values(collector, values)
    return _issued(collector, kind, arguments, user, leg)


@transaction.atomic
def _issued(collector, kind, arguments, user, leg) -> CollectorCommand:
    if kind in (CollectorCommand.Kind.START_LOGGING, CollectorCommand.Kind.STOP_LOGGING):
        allowed, reason = logging_control(collector, leg)
        starting = kind == CollectorCommand.Kind.START_LOGGING
        if not allowed:
            raise RuleViolation(reason)
        if starting == collector.logging:
            raise RuleViolation(
                gettext("Logging is already on.")
                if starting
                else gettext("Logging is already off.")
            )
        if leg is not None:
            arguments.setdefault("leg", leg.pk)
    elif kind == CollectorCommand.Kind.SNAPSHOT:
        allowed, reason = snapshot_control(collector)
        if not allowed:
            raise RuleViolation(reason)
    return CollectorCommand.objects.create(
        collector=collector, kind=kind, arguments=arguments, issued_by=user
    )


def stop_logging_into(legs) -> list[CollectorCommand]:
    """Ending a leg, shift or test event stops logging into it first.

    Connected to :data:`events.services.logs.closing`, so the REST API, the
    GUI and Django admin all get it.  The stop order is stored in the same
    transaction as the end; the collector carries it out at its next beat
    (within a second), and until then the closed leg refuses its writes.
    """
    commands = []
    for collector in Collector.objects.select_for_update().filter(logging=True, leg__in=legs):
        pending = collector.commands.filter(
            kind=CollectorCommand.Kind.STOP_LOGGING, done__isnull=True
        ).exists()
        if not pending:
            commands.append(
                CollectorCommand.objects.create(
                    collector=collector,
                    kind=CollectorCommand.Kind.STOP_LOGGING,
                    arguments={"reason": "The leg it logged into was ended."},
                )
            )
    return commands


def _on_closing(sender, legs, **kwargs) -> None:
    stop_logging_into(legs)


def connect() -> None:
    closing.connect(_on_closing, dispatch_uid="ftt-stop-logging-before-end")


# --- collector side ---------------------------------------------------------------------


# A change in one of these is announced, so open browsers redraw the collector panel.
_ANNOUNCED = ("logging", "leg_id", "state", "stopped", "vehicle_id", "disk")


def _newly_missed(before: dict | None, collector: Collector) -> int:
    """GPS fixes the collector dropped since the last heartbeat of this run (a
    publisher's own gaps are not lost fixes: collector/losses.py)."""

    def missed(inputs) -> int:
        return int(((inputs or {}).get("gps_fix") or {}).get("dropped") or 0)

    now = missed(collector.inputs)
    if before is None or before["pid"] != collector.pid:
        return now  # a new run counts from 0
    return max(0, now - missed(before["inputs"]))


@transaction.atomic
def heartbeat(name: str, **fields) -> Collector:
    """Register or refresh a collector; ``fields`` are Collector columns."""
    fields["last_seen"] = timezone.now()
    before = Collector.objects.filter(name=name).values(*_ANNOUNCED, "pid", "inputs").first()
    collector, _ = Collector.objects.update_or_create(name=name, defaults=fields)
    if collector.leg_id is not None and collector.logging:
        count_missed_fixes(collector.leg_id, _newly_missed(before, collector))
    if before is not None:
        before = {key: before[key] for key in _ANNOUNCED}
    after = {key: getattr(collector, key) for key in _ANNOUNCED}
    if before != after:
        announce(
            Announcement.Kind.COLLECTOR,
            collector,
            collector.leg,
            {"collector": collector.pk, "logging": collector.logging, "online": True},
        )
    return collector


def take_commands(collector: Collector) -> list[CollectorCommand]:
    """The collector's open commands, oldest first, marked as taken."""
    # A collector asks four times a second and nearly always finds nothing: one
    # read then, not a transaction of four statements (CPU and a core's wait on
    # a robot that is busy driving).
    if not CollectorCommand.objects.filter(collector=collector, done__isnull=True).exists():
        return []
    return _take_open_commands(collector)


@transaction.atomic
def _take_open_commands(collector: Collector) -> list[CollectorCommand]:
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
    feed.append(
        Announcement.Kind.COMMAND,
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
    """Add to the change feed; call inside the transaction that stored the data."""
    return feed.append(
        kind,
        collector_id=collector.pk if collector else None,
        leg_id=leg.pk if leg else None,
        payload=payload,
    )


@transaction.atomic
def mark_stopped(collector: Collector) -> None:
    Collector.objects.filter(pk=collector.pk).update(
        stopped=timezone.now(), logging=False, last_seen=timezone.now()
    )
    announce(Announcement.Kind.COLLECTOR, collector, None, {"online": False})
