"""Black-box snapshots in the API: listed and downloaded like images, per role."""

from datetime import timedelta

import pytest
from django.utils import timezone

from common import roles
from telemetry.models import Recording
from telemetry.services.attachments import attach_recording
from tests.support.mcap_files import read_mcap, write_fixes

pytestmark = pytest.mark.django_db


@pytest.fixture
def recording(auto_master, media_root, tmp_path):
    path = tmp_path / "snapshot-1.mcap"
    topics = write_fixes(path, [50.0, 51.0, 52.0])
    start = timezone.now()
    return attach_recording(
        auto_master, path=path, start=start, end=start + timedelta(seconds=30), topics=topics
    )


def download(client, url):
    response = client.get(url.removeprefix("http://testserver"))
    return response, b"".join(getattr(response, "streaming_content", [])) or response.content


@pytest.mark.parametrize("role", [roles.VIEWER, roles.OPERATOR])
def test_viewers_and_operators_list_and_download_snapshots(api_client, recording, role, tmp_path):
    client = api_client(role)
    listed = client.get("/api/recordings/", {"segment": recording.segment_id})
    assert listed.status_code == 200
    (row,) = listed.json()["results"]
    assert row["name"] == "snapshot-1.mcap"
    assert row["duration"] == 30.0 and row["message_count"] == 3
    assert row["topics"] == {"/gps_fix": {"type": "sensor_msgs/msg/NavSatFix", "count": 3}}
    response, content = download(client, row["file"])
    assert response.status_code == 200
    assert row["size"] == len(content)
    (tmp_path / "back.mcap").write_bytes(content)
    back = read_mcap(tmp_path / "back.mcap")
    assert [m.latitude for _, _, m in back["messages"]] == [50.0, 51.0, 52.0]


def test_without_a_role_nothing_is_listed_or_downloaded(api_client, recording):
    url = api_client(roles.VIEWER).get(f"/api/recordings/{recording.pk}/").json()["file"]
    assert api_client(None).get("/api/recordings/").status_code == 403
    assert api_client(anonymous=True).get("/api/recordings/").status_code == 401
    assert download(api_client(None), url)[0].status_code == 403
    assert download(api_client(anonymous=True), url)[0].status_code == 403


def test_only_operators_delete_and_nobody_uploads(api_client, recording):
    assert api_client(roles.VIEWER).delete(f"/api/recordings/{recording.pk}/").status_code == 403
    assert api_client(roles.OPERATOR).post("/api/recordings/", {}).status_code == 405
    assert api_client(roles.OPERATOR).delete(f"/api/recordings/{recording.pk}/").status_code == 204
    assert not Recording.objects.exists()


def test_why_a_snapshot_was_cut_reads_in_the_readers_language(
    auto_master, api_client, media_root, tmp_path
):
    path = tmp_path / "snapshot-2.mcap"
    start = timezone.now()
    attach_recording(
        auto_master,
        path=path,
        start=start,
        end=start + timedelta(seconds=30),
        topics=write_fixes(path, [50.0]),
        reason="switch to ITO",  # as the collector keeps it
    )
    client = api_client(roles.VIEWER)
    german = client.get("/api/recordings/", HTTP_ACCEPT_LANGUAGE="de").json()["results"]
    english = client.get("/api/recordings/", HTTP_ACCEPT_LANGUAGE="en").json()["results"]
    assert [r["reason"] for r in german] == ["Wechsel zu ITO"]
    assert [r["reason"] for r in english] == ["switch to ITO"]
