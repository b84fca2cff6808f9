"""The rules of the log hierarchy that every writer shares.

The services open entries "now" and close what they replace; the archive and
legacy importers write historical rows and refuse what would break a rule.
Both ask the same questions here, so the rules exist once.
"""

from django.core.exceptions import PermissionDenied
from django.db.models import QuerySet
from django.utils.translation import gettext as _

from common import roles
from events.models import Leg, Segment, SegmentType, Shift, Vehicle
from events.selectors.robots import robot_vehicles


def open_shifts_of_vehicle(vehicle_id: int) -> QuerySet[Shift]:
    """A vehicle drives in one shift at a time: at most one of these is open."""
    return Shift.objects.filter(vehicle_id=vehicle_id, end__isnull=True)


def open_legs_of_shift(shift_id: int) -> QuerySet[Leg]:
    """A shift has at most one open leg."""
    return Leg.objects.filter(shift_id=shift_id, end__isnull=True)


def open_legs_under(*, test_event=None, shift=None, leg=None) -> QuerySet[Leg]:
    """The open legs that ending a test event, a shift or a leg ends with it
    (name one); ending stops logging into them (``closing``)."""
    if test_event is not None:
        return Leg.objects.filter(shift__test_event=test_event, end__isnull=True)
    if shift is not None:
        return Leg.objects.filter(shift=shift, end__isnull=True)
    return Leg.objects.filter(pk=leg.pk, end__isnull=True)


def open_masters_of_leg(leg_id: int) -> QuerySet[Segment]:
    """A leg has at most one open master segment: the mode the robot is in now."""
    return Segment.objects.masters().filter(leg_id=leg_id, end__isnull=True)


def open_segments_of_leg(leg_id: int) -> QuerySet[Segment]:
    """The leg's open master and its open reasons (closing a master closes its
    reasons), in one read: what a change of mode closes."""
    return Segment.objects.filter(leg_id=leg_id, end__isnull=True)


def open_take_overs(leg_ids) -> QuerySet[Segment]:
    """Each leg's open take-over first: the newest open reason under the open ITO
    master (quick reasons annotate it, whatever row the operator has selected)."""
    return Segment.objects.filter(
        leg_id__in=leg_ids,
        parent__end__isnull=True,
        parent__segment_type_id=SegmentType.ITO,
        end__isnull=True,
    ).order_by("leg_id", "-start", "-id")


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


def vehicle_id_of(entry) -> int | None:
    """The vehicle a shift, leg or segment was logged for; None for rows of no vehicle
    (catalogues, pose sources).  Rows below a segment (poses, images) are written
    by naming their segment, and a map by naming its shift."""
    if isinstance(entry, Vehicle):
        return entry.pk
    if isinstance(entry, Shift):
        return entry.vehicle_id
    if isinstance(entry, Leg):
        return entry.shift.vehicle_id
    if isinstance(entry, Segment):
        return entry.leg.shift.vehicle_id
    return None


def may_reach(user, entry) -> bool:
    """Whether :func:`check_robot_target` lets ``user`` at ``entry``, without its
    message (no query when the entry's shift is loaded and the robot's vehicles
    are known)."""
    if not roles.is_robot(user):
        return True
    vehicle_id = vehicle_id_of(entry)
    return vehicle_id is None or vehicle_id in robot_vehicles(user)


def check_robot_target(user, entry) -> None:
    """A robot account reads and writes only its own vehicles and their shifts, legs
    and segments; everyone else passes (their role decides).  Refuses with
    PermissionDenied naming both vehicles."""
    if may_reach(user, entry):
        return
    vehicle_id = vehicle_id_of(entry)
    own = robot_vehicles(user)
    name = user.get_username()
    if not own:
        raise PermissionDenied(
            _(
                "Robot account '%(name)s' is bound to no vehicle, so it may not log anything; "
                "an administrator binds it to its vehicle in Django admin."
            )
            % {"name": name}
        )
    bound = ", ".join(sorted(own.values()))
    key = Vehicle.objects.filter(pk=vehicle_id).values_list("key", flat=True).first()
    if isinstance(entry, Vehicle):
        raise PermissionDenied(
            _("Robot account '%(name)s' logs only for vehicle %(bound)s, not for vehicle %(key)s.")
            % {"name": name, "bound": bound, "key": key}
        )
    what = f"{entry._meta.verbose_name} {entry.pk}"
    raise PermissionDenied(
        _(
            "Robot account '%(name)s' logs only for vehicle %(bound)s; "
            "%(what)s belongs to vehicle %(key)s."
        )
        % {"name": name, "bound": bound, "what": what, "key": key}
    )
