"""Opening, editing, closing and re-opening test events, shifts and legs."""

import uuid
from datetime import datetime

from django.core.exceptions import ValidationError
from django.db import transaction
from django.db.models import F
from django.dispatch import Signal
from django.utils.translation import gettext as _

from common.errors import RuleViolation
from common.retries import stored_row
from events import rules
from events.feed import announce_and_return
from events.models import Leg, Segment, Shift, TestEvent, Vehicle
from events.services.common import (
    apply_fields,
    check_fields,
    instant,
    lock,
    next_number,
    require_not_before,
    require_open,
)
from events.services.finality import require_amendable

TEST_EVENT_FIELDS = ("location", "version", "time_zone", "language", "note")
SHIFT_FIELDS = (
    "performer",
    "test_administrator",
    "test_director",
    "safety_officer",
    "robot_operator",
    "test_intent",
    "workspace",
    "vehicle",
    "note",
)
LEG_FIELDS = ("weather", "default_pose_source", "note", "recording", "test_case")

# Sent inside the closing transaction, before anything is closed, with the
# legs that an explicit "end" closes (``legs``: a queryset of open legs).  The
# collector link stops logging into them (rosbridge_app.services.collectors):
# ending a level stops logging first, whoever ends it.  A leg closed because a
# new one starts in the same shift is not announced: the collector follows
# the vehicle's open leg.
closing = Signal()


def _announce_closing(legs) -> None:
    closing.send(sender=Leg, legs=legs)


def _create(model, uid: uuid.UUID | None, **values):
    obj = model(**values)
    if uid is not None:
        obj.uid = uid
    obj.full_clean(validate_unique=False, validate_constraints=False)
    obj.save()
    return announce_and_return(obj)


# --- test events ---------------------------------------------------------------------------


@transaction.atomic
def create_test_event(*, uid=None, at: datetime | None = None, **fields) -> TestEvent:
    check_fields(fields, TEST_EVENT_FIELDS)
    # A test event hangs under nothing: a retry names the same place (a
    # recording imported again from another copy may word its note otherwise).
    if existing := stored_row(TestEvent, uid, location=fields.get("location", "")):
        return existing
    return _create(TestEvent, uid, start=instant(at), **fields)


@transaction.atomic
def update_test_event(event: TestEvent, **fields) -> TestEvent:
    event = lock(event)
    require_amendable(pk=event.pk)
    apply_fields(event, fields, TEST_EVENT_FIELDS)
    event.save(update_fields=list(fields))
    return announce_and_return(event)


@transaction.atomic
def close_test_event(event: TestEvent, at: datetime | None = None) -> TestEvent:
    event = lock(event)
    at = instant(at)
    require_open(event, _("Test event '%(name)s'") % {"name": event})
    require_not_before(event, at, _("Test event '%(name)s'") % {"name": event})
    _announce_closing(rules.open_legs_under(test_event=event))
    # Top-down locks (event, shift, leg), the order the writers below use too.
    for shift in event.shifts.select_for_update().filter(end__isnull=True):
        _close_shift(shift, at)
    event.end = at
    event.save(update_fields=["end"])
    return announce_and_return(event)


def may_reopen(row: TestEvent | Shift | Leg) -> bool:
    """Only a test event re-opens (its shifts and legs stay closed; new ones can be
    added), when it is closed and not final. The cockpit's Re-open button shows this."""
    return isinstance(row, TestEvent) and _reopen_refusal(row) is None


def _reopen_refusal(event: TestEvent) -> RuleViolation | None:
    if event.end is None:
        return RuleViolation(
            _("Test event '%(name)s' is already open.") % {"name": event}, code="open"
        )
    if event.finalised is not None:
        return RuleViolation(
            _("Test event '%(event)s' is final; it cannot be re-opened.") % {"event": event},
            code="final",
        )
    return None


@transaction.atomic
def reopen_test_event(event: TestEvent) -> TestEvent:
    event = lock(event)
    if refusal := _reopen_refusal(event):
        raise refusal
    event.end = None
    event.save(update_fields=["end"])
    return announce_and_return(event)


# --- shifts --------------------------------------------------------------------------------


@transaction.atomic
def create_shift(
    *,
    test_event: TestEvent,
    vehicle: Vehicle,
    uid=None,
    at: datetime | None = None,
    **fields,
) -> Shift:
    if existing := stored_row(Shift, uid, test_event_id=test_event.pk, vehicle_id=vehicle.pk):
        return existing
    event = lock(test_event)
    # Locking the vehicle serialises shift creation per vehicle, so two
    # operators starting a shift at once end with one open shift, not two.
    vehicle = lock(vehicle)
    at = instant(at)
    require_open(event, _("Test event '%(name)s'") % {"name": event})
    require_not_before(event, at, _("Test event '%(name)s'") % {"name": event})
    for open_shift in rules.open_shifts_of_vehicle(vehicle.pk).select_for_update():
        _close_shift(open_shift, max(at, open_shift.start))
    check_fields(fields, SHIFT_FIELDS)
    return _create(
        Shift,
        uid,
        test_event=event,
        vehicle=vehicle,
        number=next_number(event.shifts),
        start=at,
        **fields,
    )


@transaction.atomic
def update_shift(shift: Shift, **fields) -> Shift:
    shift = lock(shift)
    require_amendable(pk=shift.test_event_id)
    if "vehicle_id" in fields:
        fields["vehicle"] = Vehicle.objects.get(pk=fields.pop("vehicle_id"))
    if "vehicle" in fields and fields["vehicle"] != shift.vehicle and shift.is_open:
        vehicle = lock(fields["vehicle"])
        if rules.open_shifts_of_vehicle(vehicle.pk).exclude(pk=shift.pk).exists():
            raise RuleViolation(
                {
                    "vehicle": [
                        _("Vehicle '%(vehicle)s' already has an open shift; end it first.")
                        % {"vehicle": vehicle}
                    ]
                }
            )
    apply_fields(shift, fields, SHIFT_FIELDS)
    shift.save(update_fields=list(fields))
    return announce_and_return(shift)


@transaction.atomic
def close_shift(shift: Shift, at: datetime | None = None) -> Shift:
    shift = lock(shift)
    at = instant(at)
    require_open(shift, str(shift))
    require_not_before(shift, at, str(shift))
    _announce_closing(rules.open_legs_under(shift=shift))
    return announce_and_return(_close_shift(shift, at))


def _close_shift(shift: Shift, at: datetime) -> Shift:
    for leg in shift.legs.select_for_update().filter(end__isnull=True):
        _close_leg(leg, at)
    shift.end = at
    shift.save(update_fields=["end"])
    return shift


# --- legs ----------------------------------------------------------------------------------


@transaction.atomic
def create_leg(*, shift: Shift, uid=None, at: datetime | None = None, **fields) -> Leg:
    if existing := stored_row(Leg, uid, shift_id=shift.pk):
        return existing
    shift = lock(shift)
    at = instant(at)
    require_open(shift, str(shift))
    require_not_before(shift, at, str(shift))
    for open_leg in rules.open_legs_of_shift(shift.pk).select_for_update():
        _close_leg(open_leg, max(at, open_leg.start))
    check_fields(fields, LEG_FIELDS)
    _require_own_test_case(shift, fields)
    return _create(Leg, uid, shift=shift, number=next_number(shift.legs), start=at, **fields)


@transaction.atomic
def update_leg(leg: Leg, **fields) -> Leg:
    leg = lock(leg)
    require_amendable(shifts__legs=leg.pk)
    _require_own_test_case(leg.shift, fields)
    apply_fields(leg, fields, LEG_FIELDS)
    leg.save(update_fields=list(fields))
    return announce_and_return(leg)


@transaction.atomic
def close_leg(leg: Leg, at: datetime | None = None) -> Leg:
    leg = lock(leg)
    at = instant(at)
    require_open(leg, str(leg))
    require_not_before(leg, at, str(leg))
    _announce_closing(rules.open_legs_under(leg=leg))
    return announce_and_return(_close_leg(leg, at))


def _require_own_test_case(shift: Shift, fields: dict) -> None:
    case = fields.get("test_case")
    if case is not None and case.test_event_id != shift.test_event_id:
        raise ValidationError(
            {
                "test_case": [
                    (_("Test case %(case)s belongs to another test event.") % {"case": case.key})
                ]
            }
        )


def _close_leg(leg: Leg, at: datetime) -> Leg:
    # Children and masters alike: everything still open below ends now.
    open_segments = Segment.objects.filter(leg=leg, end__isnull=True)
    for segment in open_segments:
        segment.end = max(at, segment.start)
        segment.save(update_fields=["end"])
    leg.end = at
    leg.save(update_fields=["end"])
    return leg


def count_missed_fixes(leg_id: int, count: int) -> None:
    """Add ``count`` fixes a collector estimated lost to the leg's tally (the
    report's data quality); not an operator's change, so no change stamp."""
    if count > 0:
        Leg.objects.filter(pk=leg_id).update(fixes_missed=F("fixes_missed") + count)
