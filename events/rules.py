"""The rules of the log hierarchy that every writer shares.

The services open entries "now" and close what they replace; the archive and
legacy importers write historical rows and refuse what would break a rule.
Both ask the same questions here, so the rules exist once.
"""

from django.db.models import QuerySet

from events.models import Leg, Segment, Shift


def open_shifts_of_vehicle(vehicle_id: int) -> QuerySet[Shift]:
    """A vehicle drives in one shift at a time: at most one of these is open."""
    return Shift.objects.filter(vehicle_id=vehicle_id, end__isnull=True)


def open_legs_of_shift(shift_id: int) -> QuerySet[Leg]:
    """A shift has at most one open leg."""
    return Leg.objects.filter(shift_id=shift_id, end__isnull=True)


def open_masters_of_leg(leg_id: int) -> QuerySet[Segment]:
    """A leg has at most one open master segment: the mode the robot is in now."""
    return Segment.objects.filter(leg_id=leg_id, parent__isnull=True, end__isnull=True)


# (model, parent field, what a person calls it): an entry may only be open
# while its parent is open; closing cascades down in the services.
NESTING = (
    (Shift, "test_event", "shift"),
    (Leg, "shift", "leg"),
    (Segment, "leg", "segment"),
    (Segment, "parent", "ITO reason"),
)


def open_under_closed(model, parent: str) -> QuerySet:
    """Entries of ``model`` still open inside a closed ``parent`` (must be none)."""
    return model.objects.filter(end__isnull=True, **{f"{parent}__end__isnull": False})
