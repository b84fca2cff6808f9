"""The OpenAPI schema and docs page, and the session (GUI) side of authentication."""

from common import roles
from tests.support.pages import asset_urls, external_assets


def test_schema_lists_the_endpoints_and_the_docs_page_is_served_locally(client, db):
    schema = client.get("/api/schema/?format=json").json()
    assert schema["openapi"].startswith("3.")
    for path in (
        "/api/legs/{id}/mode/",
        "/api/segments/{id}/children/",
        "/api/vehicles/{id}/current-leg/",
        "/api/tracks/",
        "/api/token/",
    ):
        assert path in schema["paths"], path
    assert (
        "multipart/form-data" in schema["paths"]["/api/images/"]["post"]["requestBody"]["content"]
    )
    docs = client.get("/api/docs/")
    assert docs.status_code == 200
    page = docs.content.decode()
    # Swagger UI comes from our static files, not from a CDN: the field may have no internet.
    assert any("swagger-ui-dist" in url for url in asset_urls(page))
    assert external_assets(page) == []


def test_session_writes_need_the_csrf_token(role_user, leg):
    from django.test import Client

    browser = Client(enforce_csrf_checks=True)
    browser.force_login(role_user(roles.OPERATOR))
    refused = browser.post(f"/api/legs/{leg.pk}/close/")
    assert refused.status_code == 403 and "CSRF" in refused.json()["detail"]
    # What the GUI does: send the csrftoken cookie's value back in X-CSRFToken.
    secret = "k" * 32
    browser.cookies["csrftoken"] = secret
    accepted = browser.post(f"/api/legs/{leg.pk}/close/", HTTP_X_CSRFTOKEN=secret)
    assert accepted.status_code == 200
