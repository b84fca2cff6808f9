"""Announcing changes to open browsers (the write side of the live outbox).

The service layer calls :func:`announce` at the end of each write, inside the
write's transaction: the event becomes visible exactly when the change does,
and a rolled-back change announces nothing.  Readers are in
:mod:`rosbridge_app.consumers`.
"""

import logging

from django.conf import settings
from django.db import transaction

from rosbridge_app.models import Announcement

logger = logging.getLogger(__name__)

GROUP = "ftt-live"
# Kinds every subscriber gets, whatever it watches: the pickers and the
# collector panel need them.
LOG_KINDS = frozenset({"log", "deleted", "collector", "command"})
# More points than this in one batch are not inlined; the browser re-reads the track.
MAX_INLINE_POINTS = 2000
PRUNE_EVERY = 500


def _scope(obj) -> tuple[int | None, int | None, int | None]:
    """(test event, shift, leg) ids of any hierarchy or telemetry row."""
    from events.models import Leg, Segment, Shift, TestEvent

    if obj is None:
        return None, None, None
    if isinstance(obj, TestEvent):
        return obj.pk, None, None
    if isinstance(obj, Shift):
        return obj.test_event_id, obj.pk, None
    if isinstance(obj, Leg):
        shift = obj.shift
        return shift.test_event_id, shift.pk, obj.pk
    if isinstance(obj, Segment):
        return _scope(obj.leg)
    if hasattr(obj, "segment"):  # notes, images, poses
        return _scope(obj.segment)
    if hasattr(obj, "shift"):  # maps
        return _scope(obj.shift)
    return None, None, None


def announce(kind: str, obj=None, **payload) -> Announcement:
    test_event, shift, leg = _scope(obj)
    # The scope travels in the payload too: a deleted leg takes its own
    # announcements with it (foreign key), so "leg deleted" is kept leg-less.
    payload.update(test_event=test_event, shift=shift, leg=leg)
    leg_fk = None if kind == "deleted" else leg
    event = Announcement.objects.create(kind=kind, leg_id=leg_fk, payload=payload)
    if event.pk % PRUNE_EVERY == 0:
        prune()
    if getattr(settings, "REDIS_URL", ""):
        transaction.on_commit(_wake_other_processes)
    return event


def _label(obj) -> str:
    return type(obj)._meta.model_name


def announce_row(obj, *, deleted: bool = False) -> Announcement:
    """A log level, segment, note, image or map was created, changed or deleted."""
    from events.models import Leg, Shift, TestEvent

    kind = "deleted" if deleted else {"mapimage": "map"}.get(_label(obj), _label(obj))
    if not deleted and isinstance(obj, TestEvent | Shift | Leg):
        kind = "log"
    payload = {"model": _label(obj), "id": obj.pk}
    segment_id = getattr(obj, "segment_id", None)
    if segment_id is not None:
        payload["segment"] = segment_id
    return announce(kind, obj, **payload)


def announce_track(segment, rows, *, local: bool) -> Announcement | None:
    """New track points: inlined so that browsers append them without a fetch."""
    if not rows:
        return None
    payload = {"segment": segment.pk, "mode": segment.segment_type_id, "count": len(rows)}
    if len(rows) <= MAX_INLINE_POINTS:
        if local:
            payload["points"] = [[r.x, r.y] for r in rows]
        else:
            payload["points"] = [[r.point.x, r.point.y] for r in rows]
    return announce("local_poses" if local else "poses", segment, **payload)


def prune() -> int:
    """Drop announcements no browser can still need (a browser away longer reloads)."""
    from rosbridge_app.services.collectors import prune_announcements

    return prune_announcements()


def _wake_other_processes() -> None:
    # Only a shortcut: the consumers poll the outbox anyway, so a lost wake-up
    # costs at most one poll interval.
    try:
        from asgiref.sync import async_to_sync
        from channels.layers import get_channel_layer

        layer = get_channel_layer()
        if layer is not None:
            async_to_sync(layer.group_send)(GROUP, {"type": "live.wake"})
    except Exception as exc:  # noqa: BLE001 - never fail a committed write
        logger.debug("live wake-up not sent: %s", exc)


def announced(obj):
    """``return announced(row)`` at the end of a service function."""
    announce_row(obj)
    return obj
