"""A test plan's rules (events/models/plans.py) on every path that writes
one: Django admin refuses a bad case or criterion with a message at the field,
the archive import refuses it, and a criterion an older installation stored
without its value is still read by the API, the CSV and the report."""

import pytest
from django.contrib.gis.geos import MultiPolygon, Polygon
from django.core.management import call_command

from events.models import Criterion, TestCase
from events.services import logs
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import ImportRefused, import_bundle
from tests.support.accounts import staff_user
from tests.support.archives import members_of, replace_record, signed_archive
from tests.support.modes import start_auto
from tests.support.pdf import flat, pdf_text

pytestmark = pytest.mark.django_db

SQUARE = "MULTIPOLYGON(((7 50, 7.1 50, 7.1 50.1, 7 50.1, 7 50)))"
BOW_TIE = "MULTIPOLYGON(((7 50, 7.1 50.1, 7.1 50, 7 50.1, 7 50)))"
TOO_FAR_NORTH = "MULTIPOLYGON(((7 50, 7.1 50, 7.1 95, 7 95, 7 50)))"


def case_form(event, area="", **criterion):
    """The admin's add page of a test case, with one criterion."""
    fields = {"kind": "", "value": "", "text": "", **criterion}
    data = {
        "test_event": event.pk,
        "key": "gravel",
        "title": "Gravel loop",
        "description": "",
        "planned_runs": 1,
        "area": area,
        "route": "",
        "criteria-TOTAL_FORMS": 1,
        "criteria-INITIAL_FORMS": 0,
        "criteria-MIN_NUM_FORMS": 0,
        "criteria-MAX_NUM_FORMS": 1000,
    }
    data |= {f"criteria-0-{name}": value for name, value in fields.items()}
    return data


@pytest.fixture
def admin_client(client):
    client.force_login(staff_user("administrator"))
    return client


@pytest.mark.parametrize(
    ("area", "criterion", "message"),
    [
        ("", {"kind": "distance_without_intervention"}, "needs a value"),
        ("", {"kind": "runs_completed"}, "needs a value"),
        (BOW_TIE, {"kind": "runs_completed", "value": 2}, "not a valid shape"),
        (TOO_FAR_NORTH, {"kind": "runs_completed", "value": 2}, "within ±90°"),
        ("", {"kind": "interventions_per_km", "value": -1}, "at least 0"),
        ("", {"kind": "auto_time_share", "value": 250}, "between 0 and 100"),
        ("", {"kind": "runs_completed", "value": 1.5}, "whole number"),
        ("", {"kind": "forbidden_reasons"}, "at least one reason"),
        ("", {"kind": "judged", "text": "  "}, "what a person judges"),
    ],
)
def test_admin_refuses_a_bad_test_plan_with_a_message(
    admin_client, test_event, area, criterion, message
):
    answer = admin_client.post(
        "/admin/events/testcase/add/", case_form(test_event, area, **criterion)
    )
    assert answer.status_code == 200
    assert message in answer.content.decode()
    assert not TestCase.objects.exists() and not Criterion.objects.exists()


def test_admin_saves_a_good_test_plan(admin_client, test_event):
    form = case_form(test_event, SQUARE, kind="forbidden_reasons", reasons=["safety"])
    answer = admin_client.post("/admin/events/testcase/add/", form)
    assert answer.status_code == 302
    criterion = Criterion.objects.get()
    assert list(criterion.reasons.values_list("key", flat=True)) == ["safety"]


def _archive_of_a_plan(event, tmp_path, **criterion):
    TestCase.objects.create(
        test_event=event,
        key="gravel",
        title="Gravel loop",
        area=MultiPolygon(Polygon(((7, 50), (7.1, 50), (7.1, 50.1), (7, 50))), srid=4326),
    )
    export_events(tmp_path / "plan.zip", select_events())
    members = members_of((tmp_path / "plan.zip").read_bytes())
    TestCase.objects.all().delete()

    def changed(record):
        return {**record, **criterion}

    return signed_archive(replace_record(members, "test_cases", changed))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"criteria": [{"kind": "distance_without_intervention", "value": None}]}, "value"),
        ({"criteria": [{"kind": "auto_time_share", "value": 250}]}, "between 0 and 100"),
        ({"criteria": [{"kind": "auto_time_share", "value": "half"}]}, "must be a float"),
        ({"criteria": [{"kind": "forbidden_reasons", "reasons": []}]}, "at least one reason"),
        ({"criteria": [{"kind": "judged", "text": ""}]}, "what a person judges"),
        ({"area": [[[[7, 50], [7.1, 50.1], [7.1, 50], [7, 50.1], [7, 50]]]]}, "valid shape"),
    ],
)
def test_the_import_refuses_a_bad_test_plan(test_event, tmp_path, change, message):
    (tmp_path / "bad.zip").write_bytes(_archive_of_a_plan(test_event, tmp_path, **change))
    with pytest.raises(ImportRefused, match=message), open_archive(tmp_path / "bad.zip") as bundle:
        import_bundle(bundle)
    assert not TestCase.objects.exists()


def test_a_stored_criterion_without_value_is_read_everywhere(api_client, shift, tmp_path):
    # As an older installation's import could store it.
    case = TestCase.objects.create(test_event=shift.test_event, key="gravel", title="Gravel")
    Criterion.objects.create(test_case=case, kind="distance_without_intervention")
    Criterion.objects.create(test_case=case, kind="runs_completed")
    start_auto(logs.create_leg(shift=shift, test_case=case))
    viewer = api_client("viewer")
    plan = viewer.get(f"/api/reports/test-plan/{shift.test_event.pk}/")
    assert plan.status_code == 200
    verdicts = plan.json()["cases"][0]["verdicts"]
    assert [(v["verdict"], v["note"]) for v in verdicts] == [
        ("needs a judgement", "no threshold set")
    ] * 2
    csv = viewer.get(f"/api/reports/exports/{shift.test_event.pk}/test-plan.csv")
    assert csv.status_code == 200 and "no threshold set" in csv.content.decode()
    pdf = tmp_path / "report.pdf"
    event = str(shift.test_event.pk)
    call_command(
        "ftt_report", "--test-event", event, "--no-tiles", "--level", "summary", "-o", str(pdf)
    )
    assert "no threshold set" in flat(pdf_text(pdf.read_bytes(), tmp_path, layout=False))
