"""The two tables of the California DMV's annual disengagement report (form
OL 311R), with the form's columns, headers and word lists.

* The disengagement table: one row per intervention, exactly as the statistics
  count them (a master with counted reasons, ``Run.is_intervention``); its
  initiator and location come from its first counted reason.
* The mileage table: autonomous miles per vehicle and month of the reporting
  year (December to November), the statistics' AUTO distance of each run in
  the month (in the event's zone) its run starts.

FTT's own words are mapped to the form's by settings (``FTT_DMV_INITIATORS``,
``FTT_DMV_LOCATIONS``, ``FTT_DMV_LOCATION_DEFAULT``, ``FTT_DMV_DRIVERLESS_VEHICLES``;
docs/report.md), checked at start by ``reports.dmv_choices``.
"""

import calendar
import io
from collections import Counter, defaultdict
from datetime import date

from django.conf import settings

from common.spreadsheet import SafeWriter
from events.models import Segment, TestEvent, Vehicle
from reports.selectors.content import reasons_by_key
from reports.selectors.statistics import campaign_runs
from telemetry.storage.keys import GPS_TRACK

METRES_PER_MILE = 1609.344
CAPABLE = "VEHICLE IS CAPABLE OF OPERATING WITHOUT A DRIVER (Yes or No)"
DMV_COLUMNS = (
    "Manufacturer",
    "Permit Number",
    "DATE",
    "VIN NUMBER",
    CAPABLE,
    "DRIVER PRESENT (Yes or No)",
    "DISENGAGEMENT INITIATED BY (AV System, Test Driver, Remote Operator, or Passenger)",
    "DISENGAGEMENT LOCATION (Interstate, Freeway, Highway, Rural Road, Street, "
    "or Parking Facility)",
    "DESCRIPTION OF FACTS CAUSING DISENGAGEMENT",
)
_MONTHS = ("JAN", "FEB", "MAR", "APR", "MAY", "JUN", "JUL", "AUG", "SEP", "OCT", "NOV", "DEC")


def _yes(flag: bool) -> str:
    return "Yes" if flag else "No"


def _location(location_type: str) -> str:
    by_type = {key.casefold(): word for key, word in settings.FTT_DMV_LOCATIONS.items()}
    return by_type.get(location_type.strip().casefold(), settings.FTT_DMV_LOCATION_DEFAULT)


def _vin(vehicle: Vehicle) -> str:
    return vehicle.vin or vehicle.key


def _driverless(vehicle: Vehicle) -> bool:
    return vehicle.key in settings.FTT_DMV_DRIVERLESS_VEHICLES


def events_between(first: date, last: date) -> list[TestEvent]:
    return list(TestEvent.objects.filter(start__date__lte=last).exclude(end__date__lt=first))


def events_in_month(year: int, month: int) -> list[TestEvent]:
    # The month's last day, not the next month's first: December 9999 has none.
    last = date(year, month, calendar.monthrange(year, month)[1])
    return events_between(date(year, month, 1), last)


def reporting_months(year: int) -> list[tuple[int, int]]:
    """The DMV's reporting year ``year``: December of the year before to November."""
    return [(year - 1, 12)] + [(year, month) for month in range(1, 12)]


def events_in_reporting_year(year: int) -> list[TestEvent]:
    return events_between(date(year - 1, 12, 1), date(year, 11, 30))


def reporting_year_of(moment) -> int:
    """The reporting year a moment (in its own zone) belongs to."""
    return moment.year + 1 if moment.month == 12 else moment.year


def _runs_in(events: list[TestEvent], months: set[tuple[int, int]] | None):
    """(event, run, (year, month) the run starts in, in the event's zone) of ``events``,
    only those starting in ``months`` when given."""
    events = sorted(events, key=lambda e: (e.start, e.pk))
    runs = campaign_runs(events, GPS_TRACK)
    for event in events:
        tz = event.tzinfo
        for run in runs[event.pk]:
            local = run.start.astimezone(tz)
            month = (local.year, local.month)
            if months is None or month in months:
                yield event, run, month


def _vehicles(runs) -> dict[int, Vehicle]:
    ids = {run.vehicle_id for _event, run, _month in runs}
    return Vehicle.objects.in_bulk(ids)


def disengagements_csv(events: list[TestEvent], months: set[tuple[int, int]] | None = None) -> str:
    """The disengagement table of ``events`` (only runs starting in ``months``)."""
    found = [item for item in _runs_in(events, months) if item[1].is_intervention]
    vehicles = _vehicles(found)
    children = Segment.objects.filter(parent_id__in=[run.id for _e, run, _m in found])
    by_id = {c.id: c for c in children.only("id", "initiator", "location_type")}
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(DMV_COLUMNS)
    reasons = {}
    for event, run, _month in found:
        if event.pk not in reasons:
            reasons[event.pk] = reasons_by_key(event)
        counted = [s for s in run.reasons if s.reason in run.counted_reasons]
        first = by_id[counted[0].id]
        facts = "; ".join(
            " – ".join(filter(None, [reasons[event.pk][s.reason].short_description, s.obstacle]))
            for s in counted
        )
        vehicle = vehicles[run.vehicle_id]
        initiated_by = settings.FTT_DMV_INITIATORS[first.initiator]
        driverless = _driverless(vehicle)
        writer.writerow(
            [
                settings.FTT_DMV_MANUFACTURER,
                settings.FTT_DMV_PERMIT,
                run.start.astimezone(event.tzinfo).strftime("%m/%d/%Y"),
                _vin(vehicle),
                _yes(driverless),
                # A vehicle tested with a driver always has one; a driverless one
                # only when its test driver took over.
                _yes(not driverless or initiated_by == "Test Driver"),
                initiated_by,
                _location(first.location_type),
                facts,
            ]
        )
    return out.getvalue()


def mileage_columns(year: int) -> tuple[str, ...]:
    months = [f"{_MONTHS[month - 1]} {y}" for y, month in reporting_months(year)]
    return (
        "Manufacturer",
        "Permit Number",
        "VIN NUMBER",
        CAPABLE,
        "Annual Total of Disengagements",
        *months,
        "ANNUAL TOTAL",
    )


def mileage_csv(events: list[TestEvent], year: int) -> str:
    """The mileage table of reporting year ``year``: autonomous miles per vehicle
    and month (two decimals), one row per vehicle that drove or disengaged."""
    months = reporting_months(year)
    found = list(_runs_in(events, set(months)))
    vehicles = _vehicles(found)
    metres: dict[int, Counter] = defaultdict(Counter)
    disengagements = Counter()
    for _event, run, month in found:
        if run.kind == "auto":
            metres[run.vehicle_id][month] += run.distance
        if run.is_intervention:
            disengagements[run.vehicle_id] += 1
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(mileage_columns(year))
    shown = [pk for pk in vehicles if metres[pk] or disengagements[pk]]
    for vehicle_id in sorted(shown, key=lambda pk: _vin(vehicles[pk])):
        miles = [metres[vehicle_id][month] / METRES_PER_MILE for month in months]
        writer.writerow(
            [
                settings.FTT_DMV_MANUFACTURER,
                settings.FTT_DMV_PERMIT,
                _vin(vehicles[vehicle_id]),
                _yes(_driverless(vehicles[vehicle_id])),
                disengagements[vehicle_id],
                *(f"{value:.2f}" for value in miles),
                f"{sum(miles):.2f}",
            ]
        )
    return out.getvalue()
