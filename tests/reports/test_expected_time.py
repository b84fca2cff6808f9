"""A report being made says how long reports like it took: the median of the
finished ones of its kind (detail and scope), read by the server."""

from datetime import timedelta

import pytest

from reports.models import Report

pytestmark = pytest.mark.django_db


def finished(event, seconds, **options):
    row = Report.objects.create(test_event=event, status=Report.Status.DONE, options=options)
    Report.objects.filter(pk=row.pk).update(finished=row.created + timedelta(seconds=seconds))


def test_a_waiting_report_names_the_median_time_of_reports_like_it(api_client, test_event):
    for seconds in (10, 20, 90):
        finished(test_event, seconds, level="standard")
    finished(test_event, 300, level="full")
    finished(test_event, 400, level="standard", leg=1)
    waiting = Report.objects.create(test_event=test_event, options={"level": "standard"})
    first = Report.objects.create(test_event=test_event, options={"level": "summary"})
    rows = api_client("viewer").get(f"/api/reports/?test_event={test_event.pk}").json()
    rows = {r["id"]: r for r in (rows["results"] if isinstance(rows, dict) else rows)}
    assert rows[waiting.pk]["expected_seconds"] == 20.0
    # No summary was made yet: nothing to go by; a finished report needs none.
    assert rows[first.pk]["expected_seconds"] is None
    assert all(r["expected_seconds"] is None for r in rows.values() if r["status"] == "done")
