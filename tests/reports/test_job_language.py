"""A job's step and why it failed, read in the reader's language (common.deferred_text):
the row keeps the words, not one language's sentence."""

import io
import re
from datetime import UTC

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django_tasks.base import TaskResultStatus
from django_tasks_db.models import DBTaskResult

from common.jobs import recover_interrupted
from events.models import Segment, Shift
from exchange.models import ArchiveImport
from reports.models import Report
from reports.services.generation import request_comparison, request_report, run_job
from tests.support.api import download
from tests.support.field_day import field_day
from tests.support.jobs import run_queued_jobs
from tests.support.scenario import build_scenario

GERMAN = {"HTTP_ACCEPT_LANGUAGE": "de-DE,de;q=0.9"}
ENGLISH = {"HTTP_ACCEPT_LANGUAGE": "en-GB"}


def _row(client, report, **language) -> dict:
    return client.get(f"/api/reports/{report.pk}/", **language).json()


def _die_during(report, *workers) -> None:
    """The job of ``report`` was taken by ``workers`` that are gone (killed)."""
    DBTaskResult.objects.filter(args_kwargs__args=[report.pk]).update(
        status=TaskResultStatus.RUNNING, worker_ids=list(workers)
    )
    recover_interrupted()


def test_a_reports_step_and_failure_read_in_the_readers_language(scenario, api_client):
    operator = api_client("operator")
    asked = operator.post("/api/reports/", {"test_event": scenario.event.pk}, format="json")
    report = Report.objects.get(pk=asked.json()["id"])
    # No job worker runs in this test: each reader is told so in their language.
    waiting = _row(operator, report, **GERMAN)["message"]
    assert waiting == "wartet: kein Job-Worker läuft (manage.py ftt_worker starten)"
    assert _row(operator, report, **ENGLISH)["message"].startswith("waiting: no job worker runs")

    _die_during(report, "host-1-a")
    german = _row(operator, report, **GERMAN)
    assert german["status"] == "queued"
    assert german["message"] == (
        "erneut eingereiht: Der Job-Worker hielt während Versuch 1 von 2 an "
        "(Neustart oder Absturz von host-1-a)."
    )
    _die_during(report, "host-1-a", "host-2-b")
    german, english = _row(operator, report, **GERMAN), _row(operator, report, **ENGLISH)
    assert german["status"] == "failed" and german["message"] == "fehlgeschlagen"
    assert german["error"] == (
        "Der Job-Worker hielt während Versuch 2 von 2 an (Neustart oder Absturz von "
        "host-2-b). Fordern Sie den Bericht erneut an."
    )
    assert english["error"].startswith("The job worker stopped during attempt 2 of 2")
    assert english["message"] == "failed"


def test_why_a_report_could_not_be_made_reads_in_german(
    vehicle, other_vehicle, performer, media_root, api_client
):
    first, second = (
        build_scenario(vehicle, other_vehicle, performer, text=v).event for v in ("v1", "v2")
    )
    report = request_comparison([first, second])
    second.delete()
    assert run_job(report.pk).status == Report.Status.FAILED
    viewer = api_client("viewer")
    assert _row(viewer, report, **GERMAN)["error"] == (
        "Eine Testveranstaltung dieses Vergleichs wurde gelöscht; fordern Sie ihn erneut an."
    )
    assert _row(viewer, report, **ENGLISH)["error"] == (
        "A test event of this comparison was deleted; request it again."
    )


def test_a_shift_emptied_before_its_report_is_named_in_the_readers_language(scenario, api_client):
    shift = Shift.objects.filter(test_event=scenario.event).order_by("number").first()
    report = request_report(scenario.event, shift=shift.pk)
    Segment.objects.filter(leg__shift=shift).delete()
    assert run_job(report.pk).status == Report.Status.FAILED
    viewer = api_client("viewer")
    assert _row(viewer, report, **GERMAN)["error"] == (
        f"Schicht {shift.number} der Testveranstaltung {scenario.event.pk} hat noch keine "
        "Abschnitte: nichts zu berichten."
    )
    assert _row(viewer, report, **ENGLISH)["error"].startswith(f"Shift {shift.number} of test")


@pytest.mark.django_db
def test_an_archive_imports_step_reads_in_german(api_client, media_root, wipe):
    data = download(api_client("viewer"), field_day())
    wipe()
    admin = api_client("administrator")
    queued = admin.post(
        "/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart", **GERMAN
    )
    job = queued.json()["job"]
    assert queued.json()["detail"].startswith(f"Import als Job {job['id']} eingereiht. Würde ")
    assert job["message"] == "wartet: kein Job-Worker läuft (manage.py ftt_worker starten)"
    assert "Probelauf, nichts geschrieben" in job["detail"]
    assert run_queued_jobs() == 1
    german, english = (
        admin.get(job["url"], **GERMAN).json(),
        admin.get(job["url"], **ENGLISH).json(),
    )
    assert german["message"] == "fertig" and english["message"] == "done"
    changed = german["changes"]
    assert changed > 0
    assert german["detail"] == f"{changed} Zeile(n) geändert."
    assert english["detail"] == f"Changed {changed} row(s)."


@pytest.mark.django_db
def test_the_import_page_lists_the_jobs_in_german(client, api_client, role_user, media_root, wipe):
    data = download(api_client("viewer"), field_day())
    wipe()
    client.force_login(role_user("administrator"))
    archive = SimpleUploadedFile("field-day.zip", data, content_type="application/zip")
    client.post("/import/", {"archive": archive}, **GERMAN)
    waiting = client.get("/import/", **GERMAN).content.decode()
    assert "wartet: kein Job-Worker läuft" in waiting
    job = ArchiveImport.objects.get()
    assert f"{job.created.astimezone(UTC):%d.%m.%Y %H:%M}" in waiting
    run_queued_jobs()
    done = client.get("/import/", **GERMAN).content.decode()
    assert f"{ArchiveImport.objects.get().changes} Zeile(n) geändert." in done
    assert re.search(r"hinzugefügt\s+aktualisiert\s+unverändert\s+übernommen", done)
    english = client.get("/import/", **ENGLISH).content.decode()
    assert f"{job.created.astimezone(UTC):%Y-%m-%d %H:%M}" in english and "Changed " in english
