"""What an operator's action would end, read before it is done: the cockpit
asks with these names before it ends a test event, a shift or a leg, or starts
a new leg (which ends the shift's open leg).

The legs each action ends are the services' own (``events.rules``); this only
reads them with the shifts, the robots logging into them and their open
take-overs, and writes nothing.
"""

from django.utils.translation import gettext as _

from events import rules
from events.models import Leg, Shift, TestEvent
from events.selectors.labels import segment_labels
from rosbridge_app.selectors.collectors import logging_into

# action: (model, the legs it ends, whether logging into them stops)
ACTIONS = {
    "end-event": (TestEvent, lambda row: rules.open_legs_under(test_event=row), True),
    "end-shift": (Shift, lambda row: rules.open_legs_under(shift=row), True),
    "end-leg": (Leg, lambda row: rules.open_legs_under(leg=row), True),
    # A collector follows its vehicle's open leg: it logs on into the new one.
    "new-leg": (Shift, lambda row: rules.open_legs_of_shift(row.pk), False),
}


def _leg_name(leg: Leg) -> str:
    return _("%(vehicle)s · Shift %(shift)s · Leg %(leg)s") % {
        "vehicle": leg.shift.vehicle.short_description,
        "shift": leg.shift.number,
        "leg": leg.number,
    }


def ending(action: str, row) -> dict:
    """What ``action`` (a key of :data:`ACTIONS`) on ``row`` ends: the open
    shifts (ending a test event), legs, the vehicles whose collectors log into
    them now, and their open take-overs, each with the name the page shows."""
    _model, legs_of, stops = ACTIONS[action]
    legs = list(legs_of(row).select_related("shift__vehicle").order_by("shift__number", "number"))
    shifts = []
    if action == "end-event":
        shifts = [
            {"id": s.pk, "name": f"{s.vehicle.short_description} · {s}"}
            for s in row.shifts.filter(end__isnull=True)
            .select_related("vehicle")
            .order_by("number")
        ]
    names = {leg.pk: _leg_name(leg) for leg in legs}
    take_overs = rules.open_take_overs(list(names))
    labels = segment_labels(take_overs)
    by_leg = {leg.pk: leg for leg in legs}
    return {
        "action": action,
        "shifts": shifts,
        "legs": [{"id": pk, "name": name} for pk, name in names.items()],
        "vehicles": [
            {"name": c.vehicle.short_description, "collector": c.name, "leg": names[c.leg_id]}
            for c in logging_into().filter(leg_id__in=list(names))
        ],
        "take_overs": [
            {
                "id": t.pk,
                "name": f"{by_leg[t.leg_id].shift.vehicle.short_description} · {labels[t.pk]}",
            }
            for t in take_overs
        ],
        "logging_stops": stops,
    }
