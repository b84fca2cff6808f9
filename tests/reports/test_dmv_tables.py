"""The California DMV's two tables (form OL 311R) as a DMV reader reads them back:
the disengagement table and the autonomous miles per vehicle and month."""

import csv
import io

import pytest
from django.core.management import call_command
from django.core.management.base import SystemCheckError

from events.models import Vehicle
from events.services import segments
from reports.selectors.statistics import event_statistics

MILE_M = 1609.344
FORM_COLUMNS = [
    "Manufacturer",
    "Permit Number",
    "DATE",
    "VIN NUMBER",
    "VEHICLE IS CAPABLE OF OPERATING WITHOUT A DRIVER (Yes or No)",
    "DRIVER PRESENT (Yes or No)",
    "DISENGAGEMENT INITIATED BY (AV System, Test Driver, Remote Operator, or Passenger)",
    "DISENGAGEMENT LOCATION (Interstate, Freeway, Highway, Rural Road, Street, "
    "or Parking Facility)",
    "DESCRIPTION OF FACTS CAUSING DISENGAGEMENT",
]
INITIATORS = {"AV System", "Test Driver", "Remote Operator", "Passenger"}
LOCATIONS = {"Interstate", "Freeway", "Highway", "Rural Road", "Street", "Parking Facility"}
REPORTING_YEAR_2026 = ["DEC 2025"] + [
    f"{m} 2026" for m in "JAN FEB MAR APR MAY JUN JUL AUG SEP OCT NOV".split()
]


def _table(path):
    header, *rows = list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))
    return header, [dict(zip(header, row, strict=True)) for row in rows]


def _take_overs(scenario):
    """The first counted reason of each intervention (I1 on husky, I3 on jackal)."""
    return [scenario.masters[key].children.order_by("start", "id").first() for key in ("I1", "I3")]


@pytest.fixture
def dmv(settings):
    settings.FTT_DMV_MANUFACTURER = "ACME Robotics"
    settings.FTT_DMV_PERMIT = "AVT042"
    return settings


def test_the_disengagement_table_has_the_forms_columns_and_choices(scenario, dmv, tmp_path):
    husky_take_over, jackal_take_over = _take_overs(scenario)
    segments.annotate_segment(husky_take_over, initiator="other", location_type="Yard")
    segments.annotate_segment(jackal_take_over, initiator="autonomous_system", location_type="")
    husky = husky_take_over.leg.shift.vehicle
    husky.vin = "WVWZZZ1JZXW000001"
    husky.save()
    dmv.FTT_DMV_DRIVERLESS_VEHICLES = [jackal_take_over.leg.shift.vehicle.key]
    out = tmp_path / "dmv.csv"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--dmv", str(out))
    header, rows = _table(out)
    assert header == FORM_COLUMNS
    assert len(rows) == event_statistics(scenario.event).overall.interventions == 2
    for row in rows:
        assert row["Manufacturer"] == "ACME Robotics" and row["Permit Number"] == "AVT042"
        assert row[header[6]] in INITIATORS and row[header[7]] in LOCATIONS
    by_vin = {row["VIN NUMBER"]: row for row in rows}
    husky_row, jackal_row = by_vin[husky.vin], by_vin["jackal"]
    # 10:01 on 2 March 2026 in Tokyo, the event's zone.
    assert husky_row["DATE"] == "03/02/2026"
    # FTT's "other" and "yard" as the default table maps them; an empty location type
    # takes FTT_DMV_LOCATION_DEFAULT.
    assert [husky_row[header[6]], husky_row[header[7]]] == ["Passenger", "Parking Facility"]
    assert [jackal_row[header[6]], jackal_row[header[7]]] == ["AV System", "Street"]
    assert [husky_row[header[4]], husky_row[header[5]]] == ["No", "Yes"]
    assert [jackal_row[header[4]], jackal_row[header[5]]] == ["Yes", "No"]
    assert husky_row[header[8]].startswith("Safety")


def test_the_mapping_is_the_installations_table(scenario, dmv, tmp_path):
    take_over, _ = _take_overs(scenario)
    segments.annotate_segment(take_over, initiator="safety_driver", location_type="test track")
    dmv.FTT_DMV_LOCATIONS = {"test track": "Rural Road"}
    dmv.FTT_DMV_INITIATORS = {**dmv.FTT_DMV_INITIATORS, "safety_driver": "Remote Operator"}
    out = tmp_path / "dmv.csv"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--dmv", str(out))
    header, rows = _table(out)
    assert [rows[0][header[6]], rows[0][header[7]]] == ["Remote Operator", "Rural Road"]


def test_a_choice_the_form_does_not_have_stops_the_start(dmv):
    dmv.FTT_DMV_LOCATIONS = {"road": "Road"}
    dmv.FTT_DMV_INITIATORS = {"autonomous_system": "AV System"}
    with pytest.raises(SystemCheckError) as raised:
        call_command("check")
    said = str(raised.value)
    assert "'Road' is not one of Interstate, Freeway" in said
    assert "no DMV choice for the initiator 'safety_driver'" in said


def test_the_mileage_table_gives_autonomous_miles_per_vehicle_and_month(scenario, dmv, tmp_path):
    out = tmp_path / "miles.csv"
    call_command("ftt_report", "--dmv-mileage", str(out), "--year", "2026", stdout=io.StringIO())
    header, rows = _table(out)
    assert header == [
        "Manufacturer",
        "Permit Number",
        "VIN NUMBER",
        "VEHICLE IS CAPABLE OF OPERATING WITHOUT A DRIVER (Yes or No)",
        "Annual Total of Disengagements",
        *REPORTING_YEAR_2026,
        "ANNUAL TOTAL",
    ]
    stats = event_statistics(scenario.event)
    expected = {
        Vehicle.objects.get(pk=pk).key: figures.auto_distance / MILE_M
        for pk, figures in stats.by_vehicle.items()
    }
    assert {row["VIN NUMBER"] for row in rows} == set(expected) == {"husky", "jackal"}
    for row in rows:
        miles = expected[row["VIN NUMBER"]]
        assert float(row["MAR 2026"]) == pytest.approx(miles, abs=0.005)
        assert float(row["ANNUAL TOTAL"]) == pytest.approx(miles, abs=0.005)
        others = [float(row[month]) for month in REPORTING_YEAR_2026 if month != "MAR 2026"]
        assert others == [0.0] * 11
        assert row["Annual Total of Disengagements"] == "1"
        assert row["Manufacturer"] == "ACME Robotics"
    # The same table for the test event alone, and none the year after.
    alone = tmp_path / "alone.csv"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--dmv-mileage", str(alone))
    assert alone.read_text() == out.read_text()
    later = tmp_path / "later.csv"
    call_command("ftt_report", "--dmv-mileage", str(later), "--year", "2027", stdout=io.StringIO())
    assert len(_table(later)[1]) == 0


def test_the_disengagements_of_a_reporting_year(scenario, dmv, tmp_path):
    year = tmp_path / "year.csv"
    call_command("ftt_report", "--dmv", str(year), "--year", "2026", stdout=io.StringIO())
    month = tmp_path / "month.csv"
    call_command("ftt_report", "--dmv", str(month), "--month", "2026-03", stdout=io.StringIO())
    assert year.read_text() == month.read_text()
    assert len(_table(year)[1]) == 2
    call_command("ftt_report", "--dmv", str(year), "--year", "2025", stdout=io.StringIO())
    assert len(_table(year)[1]) == 0


def test_the_mileage_table_over_the_api(scenario, dmv, api_client):
    client = api_client("viewer")
    url = f"/api/reports/exports/{scenario.event.pk}/autonomous-mileage.csv"
    answer = client.get(url)
    assert answer.status_code == 200 and answer["Content-Type"].startswith("text/csv")
    header, *rows = list(csv.reader(io.StringIO(answer.content.decode())))
    assert "MAR 2026" in header and len(rows) == 2
    assert "MAR 2027" in next(
        csv.reader(io.StringIO(client.get(url + "?year=2027").content.decode()))
    )
    refused = client.get(url + "?year=soon")
    assert refused.status_code == 400 and "year" in refused.json()["errors"]


def test_the_disengagement_table_over_the_api_is_the_commands(scenario, dmv, api_client, tmp_path):
    answer = api_client("viewer").get(
        f"/api/reports/exports/{scenario.event.pk}/disengagements.csv"
    )
    assert answer.status_code == 200 and answer["Content-Type"].startswith("text/csv")
    header, *rows = list(csv.reader(io.StringIO(answer.content.decode())))
    assert header == FORM_COLUMNS and len(rows) == 2
    assert {row[6] for row in rows} <= INITIATORS and {row[7] for row in rows} <= LOCATIONS
    out = tmp_path / "dmv.csv"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--dmv", str(out))
    assert answer.content == out.read_bytes()
