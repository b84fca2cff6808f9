"""Reads of the collector link, for the GUI (see docs/collector.md)."""

from datetime import datetime, timedelta

from django.utils import timezone

from rosbridge_app.models import Collector, CollectorCommand

# Collectors beat every second; three missed beats make one offline.
OFFLINE_AFTER = timedelta(seconds=3)


def is_online(collector: Collector, now=None) -> bool:
    now = now or timezone.now()
    return collector.stopped is None and now - collector.last_seen <= OFFLINE_AFTER


def collector_status(collector: Collector, now=None) -> dict:
    """Everything the GUI shows about one collector, JSON-ready."""
    now = now or timezone.now()
    inputs = {}
    for name, info in (collector.inputs or {}).items():
        info = dict(info)
        last = info.get("last_received")
        if last:
            info["age"] = round((now - _parse(last)).total_seconds(), 1)
        inputs[name] = info
    return {
        "id": collector.pk,
        "name": collector.name,
        "vehicle": collector.vehicle.key if collector.vehicle_id else None,
        "host": collector.host,
        "online": is_online(collector, now),
        "last_seen": collector.last_seen.isoformat(),
        "logging": collector.logging,
        "leg": collector.leg_id,
        "state": collector.state,
        "hearing": collector.hearing,
        "disk": collector.disk,
        "pending": collector.pending,
        "parameters": collector.parameters,
        "topics": collector.topics,
        "inputs": inputs,
    }


def _parse(value: str):
    return datetime.fromisoformat(value)


def collectors(vehicle=None):
    qs = Collector.objects.select_related("vehicle")
    return qs.filter(vehicle=vehicle) if vehicle is not None else qs


def command(pk: int) -> CollectorCommand | None:
    return CollectorCommand.objects.filter(pk=pk).first()


def logging_into():
    """Collectors logging into a leg now, most recently heard first, with their leg's levels."""
    return (
        Collector.objects.filter(logging=True, leg__isnull=False, stopped__isnull=True)
        .select_related("vehicle", "leg__shift")
        .order_by("-last_seen")
    )
