"""A report of one shift or one leg: only its segments and its figures."""

import pytest
from django.core.management import CommandError, call_command

from events.models import Leg
from reports.documents.tables import figure_rows
from reports.models import Report
from reports.selectors.statistics import event_statistics
from reports.services.generation import run_job
from tests.support.pdf import flat, has_row, pdf_text


def segment_titles(text: str) -> list[str]:
    """The segment headings, e.g. "Leg 1 · #2 · ITO at 10:01"."""
    return [line.strip() for line in text.splitlines() if " AT " in line.upper() and "#" in line]


def assert_only(text: str, event, runs: int, left_out: str, **scope) -> None:
    """``runs`` segments, none of the shift ``left_out``, and the figures the
    statistics module computes for this scope (the same as its part of the whole)."""
    assert len(segment_titles(text)) == runs, segment_titles(text)
    assert not has_row(text, left_out)
    scoped = event_statistics(event, **scope).overall
    whole = event_statistics(event)
    key, pk = next((k, v) for k, v in scope.items())
    assert scoped == getattr(whole, f"by_{key}")[pk]
    for label, value in figure_rows(scoped):
        assert has_row(text, label, value), (label, value)
    assert not has_row(text, "Total distance", figure_rows(whole.overall)[0][1])


def test_a_shift_report_over_the_api_has_only_that_shift(scenario, api_client, tmp_path):
    second = scenario.shifts[1]
    response = api_client("operator").post(
        "/api/reports/",
        {"test_event": scenario.event.pk, "shift": second.pk, "options": {"level": "full"}},
        format="json",
    )
    assert response.status_code == 202, response.json()
    assert response.json()["scope"] == "Shift 2"  # what the GUI's report list shows
    report = run_job(response.json()["id"])
    assert report.status == Report.Status.DONE, report.error
    text = pdf_text(report.pdf.read(), tmp_path)

    assert "· Shift 2" in flat(text) and has_row(text, "Report of", "Shift 2")
    # The four runs of shift 2, none of shift 1 (both shifts' legs are "Leg 1").
    assert_only(text, scenario.event, 4, "Shift 1", shift=second.pk)


def test_a_leg_report_from_the_command_has_only_that_leg(scenario, tmp_path):
    leg = Leg.objects.get(shift=scenario.shifts[0])
    output = tmp_path / "leg.pdf"
    call_command("ftt_report", "--leg", str(leg.pk), "--no-tiles", "-o", str(output))
    text = pdf_text(output.read_bytes(), tmp_path)

    # In the title (wrapped there) and in the statistics.
    assert "· Shift 1 · Leg 1" in flat(text) and has_row(text, "Report of", "Shift 1 · Leg 1")
    assert_only(text, scenario.event, 3, "Shift 2", leg=leg.pk)
    assert "Jackal" not in text  # shift 2's vehicle


def test_a_leg_of_another_test_event_is_refused(scenario, open_scenario, api_client):
    other = Leg.objects.get(shift__test_event=open_scenario)
    operator = api_client("operator")
    response = operator.post(
        "/api/reports/",
        {"test_event": scenario.event.pk, "leg": other.pk},
        format="json",
    )
    assert response.status_code == 400
    assert f"Leg {other.pk} is not part of test event" in response.json()["errors"]["leg"][0]
    response = operator.post(
        "/api/reports/",
        {"test_event": scenario.event.pk, "shift": other.shift_id},
        format="json",
    )
    assert response.status_code == 400
    assert "not part of test event" in response.json()["errors"]["shift"][0]
    assert Report.objects.count() == 0
    with pytest.raises(CommandError, match="not part of shift"):
        call_command("ftt_report", "--shift", str(scenario.shifts[0].pk), "--leg", str(other.pk))
