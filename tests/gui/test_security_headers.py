"""Every main page carries the security headers, a strict CSP among them."""

import re

import pytest
from django.contrib.auth.models import User

from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db

PAGES = ["/", "/admin/", "/admin/events/segment/", "/api/docs/", "/import/"]


@pytest.fixture
def signed_in(client):
    client.force_login(User.objects.create_superuser("root", password="pw"))
    return client


@pytest.mark.parametrize("path", ["/login/", *PAGES])
def test_main_pages_send_security_headers(client, path):
    if path != "/login/":
        client.force_login(User.objects.create_superuser("root", password="pw"))
    response = client.get(path)
    assert response.status_code == 200
    policy = dict(
        part.strip().split(" ", 1) for part in response["Content-Security-Policy"].split(";")
    )
    assert policy["script-src"] == "'self'"
    assert policy["default-src"] == "'self'"
    assert policy["object-src"] == "'none'" and policy["frame-ancestors"] == "'none'"
    assert response["X-Content-Type-Options"] == "nosniff"
    assert response["X-Frame-Options"] == "DENY"
    assert response["Referrer-Policy"] == "same-origin"


def test_api_docs_start_without_an_inline_script(signed_in):
    page = signed_in.get("/api/docs/").content.decode()
    assert "<script>" not in page


def test_admin_forms_run_under_the_strict_policy(client, leg):
    """No inline script on an admin form with a map field: nothing the CSP would block."""

    client.force_login(User.objects.create_superuser("root", password="pw"))
    segment = start_auto(leg)
    form = client.get(f"/admin/events/segment/{segment.pk}/change/").content.decode()
    assert not re.search(r"<script(?![^>]*\bsrc=)[^>]*>", form)
