"""The GUI's archive download, the administrators' import and backup endpoints."""

import io
import os
import zipfile

import pytest

from events.models import TestEvent
from telemetry.models import Pose
from tests.support.api import download
from tests.support.field_day import field_day
from tests.support.jobs import run_queued_jobs
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db


def test_viewer_downloads_an_archive_and_administrator_imports_it(api_client, media_root, wipe):
    event = field_day()
    data = download(api_client("viewer"), event)
    assert "data/poses.jsonl" in zipfile.ZipFile(io.BytesIO(data)).namelist()
    before = snapshot()
    wipe()

    admin = api_client("administrator")
    dry = admin.post(
        "/api/archives/import/",
        {"archive": io.BytesIO(data), "dry_run": "true"},
        format="multipart",
    )
    assert dry.status_code == 200 and dry.json()["counts"]["poses"]["added"] == 15
    assert not Pose.objects.exists()

    queued = admin.post("/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart")
    assert queued.status_code == 202 and queued.json()["changes"] > 0
    job = queued.json()["job"]
    assert job["status"] == "queued" and not Pose.objects.exists()
    assert run_queued_jobs() == 1  # what manage.py ftt_worker does
    done = admin.get(job["url"]).json()
    assert done["status"] == "done" and done["changes"] == queued.json()["changes"]
    assert snapshot() == before
    again = admin.post("/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart")
    assert again.json()["changes"] == 0
    run_queued_jobs()
    assert admin.get(again.json()["job"]["url"]).json()["changes"] == 0
    assert api_client("operator").get(job["url"]).status_code == 403


def test_an_import_that_fails_in_the_worker_records_why_and_deletes_the_upload(
    api_client, media_root, wipe
):
    from events.services import logs
    from exchange.models import ArchiveImport
    from tests.support.field_day import T0, configuration

    data = download(api_client("viewer"), field_day(close=False))
    wipe()
    admin = api_client("administrator")
    queued = admin.post("/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart")
    assert queued.status_code == 202
    kept = ArchiveImport.objects.get().path
    # Between the check and the worker, someone opens a shift the archive also has open.
    vehicle, *_ = configuration()
    logs.create_shift(test_event=logs.create_test_event(at=T0), vehicle=vehicle, at=T0)
    run_queued_jobs()
    job = admin.get(queued.json()["job"]["url"]).json()
    assert job["status"] == "failed" and "already has an open shift" in job["error"]
    assert not Pose.objects.exists()
    assert not os.path.exists(kept)


def test_import_and_backup_are_for_administrators_only(api_client, media_root):
    event = field_day()
    data = download(api_client("viewer"), event)
    operator = api_client("operator")
    refused = operator.post(
        "/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart"
    )
    assert refused.status_code == 403
    assert operator.get("/api/backup/").status_code == 403
    assert api_client(anonymous=True).get(f"/api/test-events/{event.pk}/archive/").status_code in (
        401,
        403,
    )


def test_damaged_upload_is_refused_with_a_message(api_client, media_root):
    response = api_client("administrator").post(
        "/api/archives/import/", {"archive": io.BytesIO(b"PK\x03\x04 rubbish")}, format="multipart"
    )
    assert response.status_code == 400
    assert "not an FTT archive" in response.json()["detail"]
    assert not TestEvent.objects.exists()


def test_administrator_downloads_a_backup(api_client, media_root):
    field_day()
    response = api_client("administrator").get("/api/backup/")
    assert response.status_code == 200
    backup = zipfile.ZipFile(io.BytesIO(b"".join(response.streaming_content)))
    names = backup.namelist()
    assert any(n.startswith("database/") for n in names)
    assert sum(n.startswith("media/") for n in names) == 2


def test_import_that_conflicts_with_data_here_is_409_and_changes_nothing(
    api_client, media_root, wipe
):
    from events.services import logs
    from tests.support.field_day import T0, configuration

    data = download(api_client("viewer"), field_day(close=False))
    wipe()
    vehicle, *_ = configuration()
    logs.create_shift(test_event=logs.create_test_event(at=T0), vehicle=vehicle, at=T0)
    before = snapshot()
    response = api_client("administrator").post(
        "/api/archives/import/", {"archive": io.BytesIO(data)}, format="multipart"
    )
    assert response.status_code == 409
    assert "already has an open shift" in response.json()["detail"]
    assert "Nothing was imported" in response.json()["detail"]
    assert snapshot() == before
