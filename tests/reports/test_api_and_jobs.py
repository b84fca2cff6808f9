"""Statistics, report jobs and exports over the API; background generation."""

import json
import signal

import pytest
from django_tasks.base import TaskResultStatus
from django_tasks_db.models import DBTaskResult

from reports.models import Report
from reports.services import generation
from reports.services.generation import request_report, run_job
from tests.support.api import streamed
from tests.support.jobs import run_queued_jobs, worker_processes
from tests.support.pdf import flat, pdf_text
from tests.support.ros import wait_for
from tests.support.scenario import STEP_M


def test_statistics_endpoint_returns_the_selector_figures(scenario, api_client):
    response = api_client("viewer").get(f"/api/reports/statistics/{scenario.event.pk}/")
    assert response.status_code == 200
    data = response.json()
    assert data["overall"]["interventions"] == 2
    assert data["overall"]["auto_distance"] == pytest.approx(13 * STEP_M)
    assert data["overall"]["mdbi"]["value"] == pytest.approx(13 * STEP_M / 2)
    assert data["overall"]["mdbi"]["censored"] is False
    s1 = str(scenario.shifts[0].pk)
    assert data["shifts"][s1]["auto_seconds"] == 340
    assert "MDBI" in data["formulas"]
    labels = {row["id"]: row["label"] for row in data["segments"]}
    assert labels[scenario.masters["I1"].id] == "Leg 1 · #2"
    assert labels[scenario.masters["I3"].id] == "Leg 1 · #4"


def test_statistics_need_a_role_and_a_valid_mode(scenario, api_client):
    url = f"/api/reports/statistics/{scenario.event.pk}/"
    assert api_client(anonymous=True).get(url).status_code == 401
    assert api_client(None).get(url).status_code == 403
    response = api_client("viewer").get(url + "?mode=mars")
    assert response.status_code == 400
    assert "mode" in response.json()["errors"]
    assert api_client("viewer").get("/api/reports/statistics/999999/").status_code == 404


def test_viewer_cannot_request_a_report(scenario, api_client):
    response = api_client("viewer").post(
        "/api/reports/", {"test_event": scenario.event.pk}, format="json"
    )
    assert response.status_code == 403


def test_request_returns_at_once_and_the_worker_makes_a_downloadable_pdf(
    scenario, api_client, settings, tmp_path
):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    operator = api_client("operator")
    response = operator.post(
        "/api/reports/",
        {"test_event": scenario.event.pk, "options": {"name": "Bericht", "no_tiles": True}},
        format="json",
    )
    assert response.status_code == 202
    body = response.json()
    assert body["status"] == "queued" and body["download"] is None
    # Nobody runs jobs in this test, and the report says so.
    assert "no job worker runs" in body["message"]
    assert DBTaskResult.objects.get().status == TaskResultStatus.READY

    assert run_queued_jobs() == 1  # what manage.py ftt_worker does
    report = Report.objects.get(pk=body["id"])
    assert report.status == Report.Status.DONE and report.progress == 1.0
    listed = api_client("viewer").get(f"/api/reports/?test_event={scenario.event.pk}").json()
    assert [r["id"] for r in listed] == [body["id"]]
    assert listed[0]["download"].endswith(f"/api/reports/{body['id']}/pdf/")
    pdf = api_client("viewer").get(f"/api/reports/{body['id']}/pdf/")
    assert pdf.status_code == 200
    text = flat(pdf_text(b"".join(pdf.streaming_content), tmp_path))
    assert "Bericht" in text and scenario.event.location in text


def test_every_report_is_kept_per_test_event(scenario, tmp_path):
    request_report(scenario.event, {"no_tiles": True})
    second = request_report(scenario.event, {"no_tiles": True, "name": "zwei"})
    assert run_queued_jobs() == 2
    kept = Report.objects.filter(test_event=scenario.event, status="done")
    assert kept.count() == 2
    assert len({r.pdf.name for r in kept}) == 2
    assert "zwei" in flat(pdf_text(Report.objects.get(pk=second.pk).pdf.read(), tmp_path))


def test_bad_requests_are_refused_before_queueing(scenario, api_client, db):
    from events.services import logs

    operator = api_client("operator")
    empty = logs.create_test_event(location="leer")
    response = operator.post("/api/reports/", {"test_event": empty.pk}, format="json")
    assert response.status_code == 409
    assert "no segments" in response.json()["detail"]
    for options, field in (
        ({"colour": 1}, "colour"),
        ({"version": 2}, "version"),
        ({"recipient_address": "one line"}, "recipient_address"),
        ({"tile_url": "http://10.0.0.1/{z}/{x}/{y}.png"}, "tile_url"),  # no fetching for users
        ({"logo": "/etc/hostname"}, "logo"),  # no reading server files for users
    ):
        response = operator.post(
            "/api/reports/", {"test_event": scenario.event.pk, "options": options}, format="json"
        )
        assert response.status_code == 400, options
        assert field in " ".join(response.json()["errors"]["options"])
    assert Report.objects.count() == 0


def test_one_account_may_have_only_so_many_reports_waiting(scenario, api_client, settings):
    settings.FTT_MAX_WAITING_REPORTS = 3
    operator, other = api_client("operator"), api_client("operator")
    body = {"test_event": scenario.event.pk, "options": {"no_tiles": True}}
    codes = [operator.post("/api/reports/", body, format="json").status_code for _ in range(5)]
    assert codes == [202, 202, 202, 429, 429]
    refused = operator.post("/api/reports/", body, format="json")
    assert "You have 3 reports waiting" in refused.json()["detail"]
    assert int(refused["Retry-After"]) > 0
    # Another account is not held up by it.
    assert other.post("/api/reports/", body, format="json").status_code == 202
    assert Report.objects.count() == 4
    # Once they are made, the account may ask again.
    run_queued_jobs()
    assert operator.post("/api/reports/", body, format="json").status_code == 202


def test_failures_are_recorded_on_the_row(scenario, monkeypatch):
    def explode(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(generation, "render_report", explode)
    report = run_job(request_report(scenario.event, {}).pk)
    assert report.status == Report.Status.FAILED
    assert "disk full" in report.error


@pytest.mark.postgis_only
@pytest.mark.django_db(transaction=True)
def test_a_report_whose_worker_is_killed_is_retried_then_failed_with_the_reason(
    vehicle, other_vehicle, performer, media_root, tmp_path
):
    from tests.support.scenario import build_scenario

    scenario = build_scenario(vehicle, other_vehicle, performer)
    workers = worker_processes(tmp_path, media_root)
    try:
        first = request_report(scenario.event, {"no_tiles": True})
        _kill_during_attempt(workers.start("worker-1"), first, 1)
        # The next worker finds the job of the dead one at once (same machine)
        # and makes the report after all.
        assert workers.start("worker-2", "--batch").popen.wait(180) == 0
        first.refresh_from_db()
        assert first.status == Report.Status.DONE, first.error
        assert scenario.event.location in flat(pdf_text(first.pdf.read(), tmp_path))
        first.pdf.close()

        second = request_report(scenario.event, {"no_tiles": True})
        _kill_during_attempt(workers.start("worker-3"), second, 1)
        _kill_during_attempt(workers.start("worker-4"), second, 2)
        assert workers.start("worker-5", "--batch").popen.wait(180) == 0
        second.refresh_from_db()
        assert second.status == Report.Status.FAILED
        assert "stopped during attempt 2 of 2" in second.error
        assert "Request the report again" in second.error
        assert not DBTaskResult.objects.filter(status=TaskResultStatus.RUNNING).exists()
    finally:
        workers.stop_all()


def _kill_during_attempt(worker, report, attempt):
    def making_it():
        job = DBTaskResult.objects.filter(args_kwargs__args=[report.pk]).first()
        return (
            job.status == TaskResultStatus.RUNNING
            and len(job.worker_ids) == attempt
            and Report.objects.filter(pk=report.pk, status=Report.Status.RUNNING).exists()
        )

    wait_for(making_it, 120, 0.1, f"attempt {attempt} of report {report.pk}")
    worker.stop(signal.SIGKILL)


def test_exports_over_the_api(scenario, api_client):
    client = api_client("viewer")
    base = f"/api/reports/exports/{scenario.event.pk}/"
    csv_response = client.get(base + "segments.csv")
    assert csv_response.status_code == 200
    assert csv_response["Content-Type"].startswith("text/csv")
    assert streamed(csv_response).decode().startswith("test_event,shift,leg,label,segment_id")
    geo = client.get(base + "tracks.geojson")
    assert geo.status_code == 200 and json.loads(streamed(geo))["type"] == "FeatureCollection"
    gpx = client.get(base + "tracks.gpx")
    assert gpx.status_code == 200 and b"<trkpt" in streamed(gpx)
    assert client.get(base + "tracks.kml").status_code == 404
