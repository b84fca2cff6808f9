"""The disengagement report in the California DMV's column layout (issue 26).

One row per intervention, exactly as the statistics count them (a master with
counted reasons, ``Run.is_intervention``); its initiator, severity and
location type come from its first counted reason.  Every row also carries
its vehicle's autonomous distance in the same scope (the statistics' AUTO
distance), so the file holds the figures a DMV report asks for.
"""

import calendar
import io
from collections import defaultdict
from datetime import date

from django.conf import settings

from common.spreadsheet import SafeWriter
from events.models import Segment, TestEvent
from reports.selectors.content import reasons_by_key
from reports.selectors.statistics import event_runs
from telemetry.storage.keys import GPS

DMV_COLUMNS = (
    "Manufacturer",
    "Permit Number",
    "DATE",
    "VIN NUMBER",
    "INITIATED BY",
    "LOCATION",
    "DESCRIPTION OF FACTS CAUSING DISENGAGEMENT",
    "SEVERITY",
    "TEST EVENT",
    "AUTONOMOUS KM OF THIS VEHICLE",
)
DMV_INITIATORS = {
    "autonomous_system": "AV System",
    "safety_driver": "Test Driver",
    "remote_operator": "Remote Operator",
    "other": "Other",
}


def events_in_month(year: int, month: int) -> list[TestEvent]:
    first = date(year, month, 1)
    # The month's last day, not the next month's first: December 9999 has none.
    last = date(year, month, calendar.monthrange(year, month)[1])
    return list(TestEvent.objects.filter(start__date__lte=last).exclude(end__date__lt=first))


def _in_month(moment, tz, month: tuple[int, int] | None) -> bool:
    local = moment.astimezone(tz)
    return month is None or (local.year, local.month) == month


def disengagements_csv(events: list[TestEvent], month: tuple[int, int] | None = None) -> str:
    """The rows of ``events`` (only those starting in ``month``, in each event's zone)."""
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(DMV_COLUMNS)
    for event in sorted(events, key=lambda e: (e.start, e.pk)):
        tz = event.tzinfo
        runs = [r for r in event_runs(event, GPS) if _in_month(r.start, tz, month)]
        auto_km = defaultdict(float)
        for run in runs:
            if run.kind == "auto":
                auto_km[run.vehicle_id] += run.distance / 1000
        interventions = [r for r in runs if r.is_intervention]
        children = Segment.objects.filter(parent_id__in=[r.id for r in interventions])
        by_id = {c.id: c for c in children.only("id", "initiator", "severity", "location_type")}
        vehicles = {s.vehicle_id: s.vehicle for s in event.shifts.select_related("vehicle").all()}
        reasons = reasons_by_key(event)
        for run in interventions:
            counted = [s for s in run.reasons if s.reason in run.counted_reasons]
            first = by_id[counted[0].id]
            facts = "; ".join(
                " – ".join(filter(None, [reasons[s.reason].short_description, s.obstacle]))
                for s in counted
            )
            vehicle = vehicles[run.vehicle_id]
            writer.writerow(
                [
                    settings.FTT_DMV_MANUFACTURER,
                    settings.FTT_DMV_PERMIT,
                    run.start.astimezone(tz).strftime("%m/%d/%Y"),
                    vehicle.vin or vehicle.key,
                    DMV_INITIATORS[first.initiator],
                    first.location_type,
                    facts,
                    first.get_severity_display(),
                    str(event),
                    f"{auto_km[run.vehicle_id]:.3f}",
                ]
            )
    return out.getvalue()
