"""A generic CRUD test suite for one API endpoint, in the style of NetBox's APIViewTestCases.

A subclass names the router ``basename``, the role that may write, which of
create / update / delete the endpoint offers, and provides fixtures:
``instance`` (an existing row), ``create_data`` and ``update_data`` (request bodies).
Every test asserts what a client would notice: status codes, the JSON error shape
and whether the row really changed in the database.
"""

import pytest
from django.db import connection
from django.test.utils import CaptureQueriesContext
from django.urls import reverse

from common import roles

ALL_OPERATIONS = ("create", "update", "delete")


def lower_role(role: str) -> str:
    return roles.ORDER[roles.ORDER.index(role) - 1]


def assert_error_shape(response, status: int):
    assert response.status_code == status, response.content
    body = response.json()
    assert isinstance(body["detail"], str) and body["detail"]
    assert isinstance(body["errors"], dict)
    return body


# The tests each operation brings; an endpoint without the operation gets its
# "is not offered" test instead (405), so no test passes without asserting.
_OPERATION_TESTS = {
    "create": (
        "test_create",
        "test_create_refused_below_write_role",
        "test_create_rejects_a_non_object_body",
    ),
    "update": ("test_update", "test_update_refused_below_write_role"),
    "delete": ("test_delete", "test_delete_refused_below_write_role"),
}


class CrudTests:
    basename: str
    write_role = roles.OPERATOR
    operations = ALL_OPERATIONS
    # Multipart endpoints (files) set this to "multipart".
    format = "json"

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        # pytest collects only callables: None removes a test from this endpoint.
        for operation, names in _OPERATION_TESTS.items():
            offered = operation in cls.operations
            for name in names:
                if not offered:
                    setattr(cls, name, None)
            if offered:
                setattr(cls, f"test_{operation}_is_not_offered", None)
        if cls.format != "json":
            cls.test_create_rejects_a_non_object_body = None

    @pytest.fixture
    def instance(self):
        raise NotImplementedError

    @pytest.fixture
    def create_data(self):
        raise NotImplementedError

    @pytest.fixture
    def update_data(self):
        raise NotImplementedError

    # --- helpers ---------------------------------------------------------------------

    def list_url(self):
        return reverse(f"{self.basename}-list")

    def detail_url(self, instance_or_pk):
        pk = getattr(instance_or_pk, "pk", instance_or_pk)
        return reverse(f"{self.basename}-detail", args=[pk])

    def model(self, instance):
        return type(instance)

    def writer(self, api_client, instance):
        """A client that may change ``instance`` (rows with an owner override this)."""
        return api_client(self.write_role)

    @staticmethod
    def results(response):
        body = response.json()
        return body["results"] if isinstance(body, dict) and "results" in body else body

    # --- reading ---------------------------------------------------------------------

    def test_list_as_viewer(self, api_client, instance):
        response = api_client(roles.VIEWER).get(self.list_url())
        assert response.status_code == 200, response.content
        assert instance.pk in [row.get("id", row.get("key")) for row in self.results(response)]

    def test_retrieve_as_viewer(self, api_client, instance):
        response = api_client(roles.VIEWER).get(self.detail_url(instance))
        assert response.status_code == 200, response.content
        assert response.json().get("id", response.json().get("key")) == instance.pk

    def test_anonymous_is_refused(self, api_client, instance):
        response = api_client(anonymous=True).get(self.list_url())
        assert_error_shape(response, 401)
        assert response["WWW-Authenticate"].startswith("Token")

    def test_user_without_role_is_refused(self, api_client, instance):
        assert_error_shape(api_client(None).get(self.list_url()), 403)

    def test_unknown_id_is_404(self, api_client, instance):
        client = api_client(roles.VIEWER)
        for missing in ("999999999", "not-an-id", "9" * 30):
            assert_error_shape(client.get(self.detail_url(missing)), 404)

    # --- writing ---------------------------------------------------------------------

    def test_create_is_not_offered(self, api_client, instance):
        response = api_client(self.write_role).post(self.list_url(), {}, format="json")
        assert_error_shape(response, 405)

    def test_update_is_not_offered(self, api_client, instance):
        response = api_client(self.write_role).patch(self.detail_url(instance), {}, format="json")
        assert_error_shape(response, 405)

    def test_delete_is_not_offered(self, api_client, instance):
        assert_error_shape(api_client(self.write_role).delete(self.detail_url(instance)), 405)
        assert self.model(instance).objects.filter(pk=instance.pk).exists()

    def test_create(self, api_client, instance, create_data):
        model = self.model(instance)
        before = model.objects.count()
        response = api_client(self.write_role).post(
            self.list_url(), create_data, format=self.format
        )
        assert response.status_code == 201, response.content
        assert model.objects.count() == before + 1
        body = response.json()
        created = model.objects.get(pk=body.get("id", body.get("key")))
        # Plain values sent are stored as sent (foreign keys by their id).
        compared = 0
        for name, value in create_data.items():
            if not isinstance(value, str | int | bool) or not hasattr(created, name):
                continue
            stored = getattr(created, name)
            stored = getattr(stored, "pk", stored)
            if isinstance(stored, type(value)):
                assert stored == value, name
                compared += 1
        assert compared, "create_data must hold at least one plain value to check"

    def test_create_refused_below_write_role(self, api_client, instance, create_data):
        model = self.model(instance)
        before = model.objects.count()
        response = api_client(lower_role(self.write_role)).post(
            self.list_url(), create_data, format=self.format
        )
        assert_error_shape(response, 403)
        assert model.objects.count() == before

    def test_create_rejects_a_non_object_body(self, api_client, instance):
        response = api_client(self.write_role).post(self.list_url(), [1, 2], format="json")
        assert_error_shape(response, 400)

    def test_update(self, api_client, instance, update_data):
        response = self.writer(api_client, instance).patch(
            self.detail_url(instance), update_data, format=self.format
        )
        assert response.status_code == 200, response.content
        instance.refresh_from_db()
        for field, value in update_data.items():
            stored = getattr(instance, field)
            assert getattr(stored, "pk", stored) == value
            assert response.json()[field] == value

    def test_update_refused_below_write_role(self, api_client, instance, update_data):
        response = api_client(lower_role(self.write_role)).patch(
            self.detail_url(instance), update_data, format=self.format
        )
        assert_error_shape(response, 403)
        before = {f: getattr(instance, f) for f in update_data}
        instance.refresh_from_db()
        assert {f: getattr(instance, f) for f in update_data} == before

    def test_delete(self, api_client, instance):
        response = self.writer(api_client, instance).delete(self.detail_url(instance))
        assert response.status_code == 204, response.content
        assert not self.model(instance).objects.filter(pk=instance.pk).exists()

    def test_delete_refused_below_write_role(self, api_client, instance):
        response = api_client(lower_role(self.write_role)).delete(self.detail_url(instance))
        assert_error_shape(response, 403)
        assert self.model(instance).objects.filter(pk=instance.pk).exists()


# --- query counts (no N+1 on list endpoints) -----------------------------------------

# The page count and the page itself; the token with its user and groups is kept
# from the client's first request (common.api.authentication).
LIST_QUERIES = 2


def assert_constant_queries(api_client, django_assert_max_num_queries, url, add_rows, *, most):
    """Queries for ``url`` after 2 rows and after 25 more must match and stay within ``most``."""
    client = api_client(roles.VIEWER)
    add_rows(2)
    # The first request also looks the token up; it is kept for the next ones.
    client.get(url)
    with CaptureQueriesContext(connection) as few:
        first = client.get(url)
    assert first.status_code == 200, first.content
    add_rows(25)
    with django_assert_max_num_queries(most):
        many = client.get(url)
    assert many.status_code == 200
    assert len(many.content) > len(first.content), "the extra rows must show up"
    with CaptureQueriesContext(connection) as again:
        client.get(url)
    assert len(again) == len(few), [q["sql"] for q in again.captured_queries]


def post_counting_queries(client, url, body):
    """POST ``body`` as JSON; returns the response, every query run, and the queries inside
    the write's transaction (under the test's own transaction that is a savepoint)."""
    with CaptureQueriesContext(connection) as captured:
        response = client.post(url, body, format="json")
    sql = [q["sql"] for q in captured.captured_queries]
    opened = [i for i, q in enumerate(sql) if q.startswith(("SAVEPOINT", "BEGIN"))]
    closed = [i for i, q in enumerate(sql) if q.startswith(("RELEASE SAVEPOINT", "COMMIT"))]
    assert len(opened) == len(closed) == 1, sql
    return response, sql, sql[opened[0] + 1 : closed[0]]


# --- downloads ------------------------------------------------------------------------


def streamed(response) -> bytes:
    """A download that grows with the data, read as a client reads it: it must be
    streamed (common.api.downloads), never made whole first."""
    assert response.streaming, "the download is not streamed"
    return b"".join(response.streaming_content)


# --- archives -------------------------------------------------------------------------


def download(client, event):
    """A test event's archive as an API client downloads it."""
    response = client.get(f"/api/test-events/{event.pk}/archive/")
    assert response.status_code == 200, response.content
    assert response["Content-Disposition"].startswith("attachment;")
    return b"".join(response.streaming_content)
