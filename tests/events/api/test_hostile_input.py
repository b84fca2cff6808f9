"""Malformed and hostile requests get a 4xx JSON answer, never a 500."""

import json

import pytest

from common import roles
from tests.support.api import assert_error_shape


@pytest.fixture
def operator(api_client):
    client = api_client(roles.OPERATOR)
    client.raise_request_exception = False
    return client


RAW_BODIES = [
    b'{"location": ',  # cut off
    b"\xff\xfe\x00garbage",  # not UTF-8
    b'{"mode": "auto", "longitude": NaN, "latitude": 1}',
    b'{"mode": "auto", "longitude": Infinity, "latitude": 1}',
    b'{"mode": "auto", "longitude": 1e400, "latitude": 1}',
    b"[" * 100_000 + b"]" * 100_000,  # deeper than Python's recursion limit
    b'"just a string"',
    b"null",
]


@pytest.mark.parametrize("body", RAW_BODIES, ids=range(len(RAW_BODIES)))
def test_broken_json_is_a_400(operator, leg, body):
    response = operator.generic(
        "POST", f"/api/legs/{leg.pk}/mode/", body, content_type="application/json"
    )
    assert_error_shape(response, 400)
    assert not leg.segments.exists()


@pytest.mark.parametrize(
    "path, payload, field",
    [
        ("/api/shifts/", {"test_event": "abc", "vehicle": 1}, "test_event"),
        ("/api/shifts/", {"test_event": 10**30, "vehicle": 1}, "test_event"),
        ("/api/shifts/", {"test_event": 1.5, "vehicle": [1]}, "test_event"),
        ("/api/shifts/", {"test_event": True, "vehicle": 1}, "test_event"),
        ("/api/legs/", {"shift": None}, "shift"),
        ("/api/legs/", {"shift": {"id": 1}}, "shift"),
        ("/api/legs/", {"shift": 1, "weather": "sun\x00ny"}, "weather"),
        ("/api/test-events/", {"location": "x" * 501}, "location"),
        ("/api/test-events/", {"location": "nul\x00byte"}, "location"),
        ("/api/test-events/", {"time_zone": "Mars/Olympus"}, "time_zone"),
        ("/api/test-events/", {"uid": "12"}, "uid"),
        ("/api/poses/", {"segment": -1, "longitude": 1, "latitude": 1}, "segment"),
        ("/api/poses/", {"segment": 1, "longitude": "1e999", "latitude": 1}, "longitude"),
        ("/api/poses/", {"segment": 1, "longitude": 1, "latitude": 1, "fix_status": 7}, None),
        ("/api/notes/", {"segment": "1 OR 1=1", "text": "x"}, "segment"),
        ("/api/vehicles/", {"key": "not a slug!", "short_description": "x"}, "key"),
    ],
)
def test_wrong_types_and_values_are_400_with_the_field(api_client, leg, path, payload, field):
    client = api_client(roles.ADMINISTRATOR)
    response = client.post(path, payload, format="json")
    body = assert_error_shape(response, 400)
    if field:
        assert field in body["errors"], body


@pytest.mark.parametrize(
    "query",
    [
        "open=maybe",
        "start_after=not-a-date",
        "start_after=10000-01-01T00:00:00Z",
        "start_before=0001-01-01T00:00:00%2B01:00",
        "start_after=9999-12-31T23:59:59-01:00",
        "test_event=abc",
        "test_event=99999999999999999999999",
        "test_event=%00",
        "mode=flying",
    ],
)
def test_bad_filters_are_400(api_client, leg, query):
    response = api_client(roles.VIEWER).get(f"/api/segments/?{query}")
    assert_error_shape(response, 400)


@pytest.mark.parametrize("query", ["page=abc", "page=999", "page=-1"])
def test_bad_pages_are_404(api_client, leg, query):
    assert_error_shape(api_client(roles.VIEWER).get(f"/api/legs/?{query}"), 404)


def test_page_size_is_capped(api_client, leg):
    response = api_client(roles.VIEWER).get(f"/api/legs/?page_size={10**30}")
    assert response.status_code == 200 and response.json()["count"] == 1


def test_unsupported_content_type_is_415(operator):
    response = operator.generic(
        "POST", "/api/test-events/", json.dumps({"location": "x"}), content_type="text/plain"
    )
    assert_error_shape(response, 415)


def test_multipart_garbage_is_a_400(api_client, shift):
    client = api_client(roles.OPERATOR)
    response = client.generic(
        "POST",
        "/api/maps/",
        b'--xx\r\nContent-Disposition: form-data; name="shift"\r\n\r\n1\r\n--x',
        content_type="multipart/form-data; boundary=xx",
    )
    assert response.status_code == 400


@pytest.mark.parametrize("path", ["/api/nothing-here/", "/api/legs/1.5/", "/api/vehicles/a.b/"])
def test_unknown_api_addresses_are_json_404(api_client, db, path):
    assert_error_shape(api_client(roles.VIEWER).get(path), 404)


def test_outside_the_api_404_stays_html(client, db):
    response = client.get("/no-such-page/")
    assert response.status_code == 404
    assert not response["Content-Type"].startswith("application/json")
