"""/media/ shows photos, maps and reports in the browser and only downloads anything else."""

import pytest
from django.contrib.auth.models import Group, User

pytestmark = pytest.mark.django_db


@pytest.fixture
def viewer(client):
    user = User.objects.create_user("vera", password="pw")
    user.groups.add(Group.objects.get(name="viewer"))
    client.force_login(user)
    return client


def _put(media_root, name: str, body: bytes) -> str:
    path = media_root / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(body)
    return f"/media/{name}"


@pytest.mark.parametrize("accel", ["", "/protected-media/"], ids=["django", "nginx"])
def test_a_stored_web_page_is_downloaded_not_shown(viewer, media_root, settings, accel):
    settings.FTT_MEDIA_ACCEL_PREFIX = accel
    url = _put(media_root, "images/x/evil.html", b"<script>alert(1)</script>")
    response = viewer.get(url)
    assert response.status_code == 200
    assert response["Content-Type"] == "application/octet-stream"
    assert response["Content-Disposition"].startswith("attachment")
    assert response["X-Content-Type-Options"] == "nosniff"


@pytest.mark.parametrize(
    "name, content_type",
    [
        ("a.png", "image/png"),
        ("a.JPG", "image/jpeg"),
        ("a.webp", "image/webp"),
        ("r.pdf", "application/pdf"),
    ],
)
def test_pictures_and_reports_are_shown_with_their_type(viewer, media_root, name, content_type):
    response = viewer.get(_put(media_root, f"x/{name}", b"data"))
    assert response["Content-Type"] == content_type
    assert not response.get("Content-Disposition", "").startswith("attachment")


def test_a_script_with_a_token_opens_a_picture_in_one_query(
    api_client, media_root, django_assert_num_queries
):
    url = _put(media_root, "images/x/a.png", b"data")
    client = api_client("viewer")
    # The token, its account and the account's roles come back together.
    with django_assert_num_queries(1):
        response = client.get(url)
    assert response.status_code == 200
    assert response["Content-Type"] == "image/png"


def test_a_wrong_or_missing_token_sees_no_picture(api_client, media_root):
    url = _put(media_root, "images/x/a.png", b"data")
    anonymous = api_client(anonymous=True)
    assert anonymous.get(url).status_code == 403
    anonymous.credentials(HTTP_AUTHORIZATION="Token not-a-token")
    assert anonymous.get(url).status_code == 403
