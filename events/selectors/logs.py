from events import rules
from events.models import Leg, Segment


def open_leg_for_vehicle(vehicle) -> Leg | None:
    """The leg a robot logs into: the open leg of its vehicle's open shift."""
    return (
        Leg.objects.select_related("shift", "shift__test_event")
        .filter(shift__vehicle=vehicle, shift__end__isnull=True, end__isnull=True)
        .first()
    )


def open_master(leg: Leg) -> Segment | None:
    return rules.open_masters_of_leg(leg.pk).first()
