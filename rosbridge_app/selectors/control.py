"""When the GUI may start or stop logging (the seeds' rule, kept in one place),
and when it may ask for a black-box snapshot.

Starting needs an online collector and an open test event, shift and leg;
stopping is always allowed while the collector logs, even when the levels
were closed elsewhere in the meantime.  A snapshot on request needs an online,
logging collector with snapshots on: it is stored on the open segment.
"""

from django.core.exceptions import ValidationError
from django.utils.translation import gettext as _

from events.models import Leg
from rosbridge_app.collector.params import SPECS, InvalidParameter, check
from rosbridge_app.models import Collector
from rosbridge_app.selectors.collectors import is_online


def logging_control(collector: Collector | None, leg: Leg | None) -> tuple[bool, str]:
    """(may the button be pressed, why not / what it does) for the selected leg."""
    if collector is None:
        return False, _("No collector has reported for this vehicle.")
    if collector.logging:
        return True, _("Stopping ends the open segment.")
    if not is_online(collector):
        return False, _("The collector is offline.")
    if leg is None:
        return False, _("Select a test event, shift and leg.")
    shift = leg.shift
    if not (leg.is_open and shift.is_open and shift.test_event.is_open):
        return False, _("Logging needs an open test event, shift and leg.")
    if shift.vehicle_id != collector.vehicle_id:
        return False, _("This collector belongs to another vehicle.")
    return True, ""


def stores_nothing(collector: Collector | None) -> str:
    """Why a collector that logs stores nothing (its leg ended or it has none), or ""."""
    if collector is None or not collector.logging or not is_online(collector):
        return ""
    leg = collector.leg
    if leg is None:
        return _("Logging into no leg: nothing is stored. Start a new leg.")
    if not leg.is_open:
        return _("Logging into %(leg)s, which has ended: nothing is stored. Start a new leg.") % {
            "leg": leg
        }
    return ""


def snapshot_control(collector: Collector | None) -> tuple[bool, str]:
    """(may "Snapshot now" be pressed, why not / what it does)."""
    if collector is None:
        return False, _("No collector has reported for this vehicle.")
    if not is_online(collector):
        return False, _("The collector is offline.")
    values = collector.parameters or {}
    if not values.get("snapshot.enabled"):
        return False, _("Snapshots are off on this robot (snapshot.enabled).")
    if not collector.logging:
        return False, _("A snapshot is stored on the open segment: start logging first.")
    before = values.get("snapshot.before", SPECS["snapshot.before"].default)
    after = values.get("snapshot.after", SPECS["snapshot.after"].default)
    return True, _(
        "Saves the robot's messages from %(before)s s before to %(after)s s after now."
    ) % {
        "before": f"{before:g}",
        "after": f"{after:g}",
    }


def check_parameter_values(collector: Collector, changes: dict) -> dict:
    """Changed values as the collector will take them, checked against the
    schema now, so a wrong value is refused with a field message at once (a
    wrong value, 400, not a state that forbids it)."""
    current = collector.parameters or {}
    errors, checked = {}, {}
    for name, value in changes.items():
        if name not in current or name not in SPECS:
            errors[name] = [_("The collector has no such parameter.")]
            continue
        try:
            checked[name] = check(name, value)
        except InvalidParameter as exc:
            errors[name] = [str(exc)]
    if errors:
        raise ValidationError(errors)
    return checked
