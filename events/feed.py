"""The write side of the change feed (:class:`events.models.Announcement`).

Every writer (services, collector, importers) adds its row here, by the ORM,
inside the transaction of its change: the feed shows the change exactly when
it is committed, and a rolled-back change announces nothing.  The live link
(:mod:`live.consumers`) reads the feed and hears its new rows
(:mod:`live.wakeup` lists every way), but the feed never calls up to it.
"""

from datetime import timedelta

from django.db import router
from django.db.models.signals import post_save
from django.utils import timezone

from events.models import Announcement, Leg, Segment, Shift, TestEvent

# Kinds every subscriber gets, whatever it watches: the pickers and the
# collector panel need them.
LOG_KINDS = frozenset({"log", "deleted", "collector", "command"})
# Kinds a fleet view gets from every leg: each robot's mode and position.
FLEET_KINDS = frozenset({"segment", "poses"})
# More points than this in one batch are not inlined; the browser re-reads the track.
MAX_INLINE_POINTS = 2000
PRUNE_EVERY = 500
# A browser away for longer than this reloads instead of catching up.
RETENTION = timedelta(hours=1)


def _scope(obj) -> tuple[int | None, int | None, int | None]:
    """(test event, shift, leg) ids of any hierarchy or telemetry row."""
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


def announce(kind: str, obj=None, *, collector_id: int | None = None, **payload) -> Announcement:
    """Add a row about ``obj`` (its test event, shift and leg are the row's scope)."""
    return _save(_about(kind, obj, collector_id=collector_id, **payload))


def _about(kind: str, obj=None, *, collector_id: int | None = None, **payload) -> Announcement:
    """The unsaved row about ``obj``."""
    test_event, shift, leg = _scope(obj)
    # The scope travels in the payload too: a deleted leg takes its own
    # announcements with it (foreign key), so "leg deleted" is kept leg-less.
    payload.update(test_event=test_event, shift=shift, leg=leg)
    leg_fk = None if kind == "deleted" else leg
    return Announcement(kind=kind, leg_id=leg_fk, collector_id=collector_id, payload=payload)


def append(kind: str, *, leg_id=None, collector_id=None, payload=None) -> Announcement:
    """Add one row to the feed as given (the collector link states its own scope)."""
    return _save(
        Announcement(kind=kind, leg_id=leg_id, collector_id=collector_id, payload=payload or {})
    )


def _save(event: Announcement) -> Announcement:
    """The one way the ORM writes a feed row (the storage port inserts a track's
    row in the statement of its figures, then :func:`written` follows)."""
    event.save(force_insert=True)
    return written(event, saved=True)


def settle(event: Announcement) -> Announcement:
    """A row handed to the storage port with its change: saved now unless the
    port inserted it in the change's statement."""
    return _save(event) if event.pk is None else written(event)


def written(event: Announcement, *, saved: bool = False) -> Announcement:
    """What follows a feed row's insert: every PRUNE_EVERY-th row also prunes,
    in the same transaction, and a row inserted by SQL (``saved`` False) is
    announced to ``post_save``'s receivers (the live wake-up) as the ORM's
    save would have."""
    if not saved:
        event._state.adding, event._state.db = False, router.db_for_write(Announcement)
        post_save.send(
            sender=Announcement, instance=event, created=True, update_fields=None, raw=False,
            using=event._state.db,
        )  # fmt: skip
    if event.pk % PRUNE_EVERY == 0:
        prune()
    return event


def _label(obj) -> str:
    return type(obj)._meta.model_name


def announce_row(obj, *, deleted: bool = False) -> Announcement:
    """A log level, segment, note, image or map was created, changed or deleted."""
    kind = "deleted" if deleted else {"mapimage": "map"}.get(_label(obj), _label(obj))
    if not deleted and isinstance(obj, TestEvent | Shift | Leg):
        kind = "log"
    payload = {"model": _label(obj), "id": obj.pk}
    segment_id = getattr(obj, "segment_id", None)
    if segment_id is not None:
        payload["segment"] = segment_id
    return announce(kind, obj, **payload)


def track_announcement(
    segment, points, *, local: bool, heading=None, inside: bool = False
) -> Announcement | None:
    """New usable track points as stored, in driving order, given as (x, y) or
    (longitude, latitude) pairs.  When they follow the track's end they are
    inlined, so that browsers append them without a fetch; ``inside`` (some lie
    between points stored before, a late batch) or too many for a row, the row
    says the segment's track changed (``"changed": true``, no points) and
    browsers draw it again from the server's track.  ``heading`` (radians, map
    frame) is the last point's, where known: the cockpit turns the robot's marker by it.
    The row is unsaved: the storage port inserts it in the statement of the
    figures it goes with (:func:`settle` follows).
    """
    if not points:
        return None
    payload = {"segment": segment.pk, "mode": segment.segment_type_id, "count": len(points)}
    if heading is not None:
        payload["heading"] = heading
    if inside or len(points) > MAX_INLINE_POINTS:
        payload["changed"] = True
    else:
        payload["points"] = [[x, y] for x, y in points]
    return _about("local_poses" if local else "poses", segment, **payload)


def prune() -> int:
    """Drop rows no browser can still need (a browser away longer reloads)."""
    cutoff = timezone.now() - RETENTION
    return Announcement.objects.filter(created__lt=cutoff).delete()[0]


def after(last_id: int, limit: int = 500) -> list[Announcement]:
    """Rows newer than ``last_id``, oldest first."""
    return list(Announcement.objects.filter(pk__gt=last_id).order_by("id")[:limit])


def newest() -> int:
    """The newest id in the feed; 0 when empty."""
    return Announcement.objects.order_by("-id").values_list("id", flat=True).first() or 0


def bounds() -> tuple[int, int]:
    """(first, last) id still in the feed; (0, 0) when empty."""
    first = Announcement.objects.order_by("id").values_list("id", flat=True).first()
    return first or 0, newest()


def announce_and_return(obj):
    """``return announce_and_return(row)`` at the end of a service function."""
    announce_row(obj)
    return obj
