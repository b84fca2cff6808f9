"""What the original's ids mean for one robot account.

"Current …" is the open entry of the token's vehicle, never another robot's
(the original took the newest open entry of the whole database). A number is
an FTT row id, refused when it belongs to another vehicle.
"""

from events.models import Leg, Segment, Shift, Vehicle
from events.rules import check_robot_target
from events.selectors.logs import open_leg_for_vehicle, open_master
from events.selectors.robots import robot_vehicles
from rosbridge_app.legacy_api.answers import LegacyRefusal


def vehicle_of(user) -> Vehicle:
    """The one vehicle the account logs for now: its only one, or the only one with
    an open leg."""
    ids = list(robot_vehicles(user))
    if not ids:
        raise LegacyRefusal(
            "AuthError", "This robot account is bound to no vehicle; an administrator binds it."
        )
    vehicles = list(Vehicle.objects.filter(pk__in=ids))
    if len(vehicles) == 1:
        return vehicles[0]
    logging = [v for v in vehicles if open_leg_for_vehicle(v) is not None]
    if len(logging) == 1:
        return logging[0]
    raise LegacyRefusal(
        "LogError",
        "This robot account is bound to several vehicles and cannot tell which one is "
        "meant; give each robot an account of its own.",
    )


def leg(user, pk: int | None) -> Leg:
    if pk is None:
        vehicle = vehicle_of(user)
        found = open_leg_for_vehicle(vehicle)
        if found is None:
            raise LegacyRefusal("LogError", f"No open leg for vehicle {vehicle.key}. Aborted.")
        return found
    return _own(user, Leg.objects.select_related("shift").filter(pk=pk).first(), f"leg {pk}")


def shift(user, pk: int | None) -> Shift:
    if pk is None:
        return leg(user, None).shift
    return _own(user, Shift.objects.filter(pk=pk).first(), f"shift {pk}")


def segment(user, pk: int | None) -> Segment:
    """The segment ``pk``, or the open master of the vehicle's leg."""
    if pk is None:
        current = leg(user, None)
        master = open_master(current)
        if master is None:
            raise LegacyRefusal("LogError", f"No open segment in {current}. Aborted.")
        return master
    found = Segment.objects.select_related("leg__shift").filter(pk=pk).first()
    return _own(user, found, f"segment {pk}")


def _own(user, entry, name: str):
    if entry is None:
        raise LegacyRefusal("LogError", f"No {name}. Aborted.")
    check_robot_target(user, entry)
    return entry
