"""The administrators' import page in the GUI."""

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile

from events.models import TestEvent
from telemetry.models import Pose
from tests.support.api import download
from tests.support.field_day import field_day
from tests.support.jobs import run_queued_jobs
from tests.support.snapshot import snapshot

pytestmark = pytest.mark.django_db


def upload(data: bytes) -> SimpleUploadedFile:
    return SimpleUploadedFile("field-day.zip", data, content_type="application/zip")


def test_administrator_previews_then_imports_an_archive(
    client, api_client, role_user, media_root, wipe
):
    data = download(api_client("viewer"), field_day())
    before = snapshot()
    wipe()
    client.force_login(role_user("administrator"))
    assert b"Import archive" in client.get("/").content

    preview = client.post("/import/", {"archive": upload(data), "dry_run": "on"})
    assert "dry run, nothing written" in preview.content.decode()
    assert not Pose.objects.exists()

    queued = client.post("/import/", {"archive": upload(data)}, follow=True).content.decode()
    # Queued for the job worker; a reload shows the list and sends nothing again.
    assert "field-day.zip" in queued and "queued" in queued
    assert 'http-equiv="refresh"' in queued
    run_queued_jobs()
    done = client.get("/import/").content.decode()
    assert "Changed" in done and "poses" in done
    assert 'http-equiv="refresh"' not in done
    assert snapshot() == before


def test_damaged_archive_is_explained_and_nothing_changes(client, role_user, media_root):
    client.force_login(role_user("administrator"))
    page = client.post("/import/", {"archive": upload(b"PK\x03\x04 rubbish")})
    assert "Nothing was imported" in page.content.decode()
    assert not TestEvent.objects.exists()


def test_operators_do_not_get_the_import_page(client, role_user):
    client.force_login(role_user("operator"))
    assert b"Import archive" not in client.get("/").content
    assert client.get("/import/").status_code == 403
    assert client.post("/import/", {"archive": upload(b"x")}).status_code == 403
