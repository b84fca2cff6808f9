"""A generic CRUD test suite for one API endpoint, in the style of NetBox's APIViewTestCases.

A subclass names the router ``basename``, the role that may write, which of
create / update / delete the endpoint offers, and provides fixtures:
``instance`` (an existing row), ``create_data`` and ``update_data`` (request bodies).
Every test asserts what a client would notice: status codes, the JSON error shape
and whether the row really changed in the database.
"""

import pytest
from django.urls import reverse

from events import roles

ALL_OPERATIONS = ("create", "update", "delete")


def lower_role(role: str) -> str:
    return roles.ORDER[roles.ORDER.index(role) - 1]


def assert_error_shape(response, status: int):
    assert response.status_code == status, response.content
    body = response.json()
    assert isinstance(body["detail"], str) and body["detail"]
    assert isinstance(body["errors"], dict)
    return body


class CrudTests:
    basename: str
    write_role = roles.OPERATOR
    operations = ALL_OPERATIONS
    # Multipart endpoints (files) set this to "multipart".
    format = "json"

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

    def test_create(self, api_client, instance, create_data):
        if "create" not in self.operations:
            response = api_client(self.write_role).post(self.list_url(), {}, format="json")
            assert_error_shape(response, 405)
            return
        model = self.model(instance)
        before = model.objects.count()
        response = api_client(self.write_role).post(
            self.list_url(), create_data, format=self.format
        )
        assert response.status_code == 201, response.content
        assert model.objects.count() == before + 1
        body = response.json()
        created = model.objects.get(pk=body.get("id", body.get("key")))
        assert created is not None

    def test_create_refused_below_write_role(self, api_client, instance, create_data):
        if "create" not in self.operations:
            return
        model = self.model(instance)
        before = model.objects.count()
        response = api_client(lower_role(self.write_role)).post(
            self.list_url(), create_data, format=self.format
        )
        assert_error_shape(response, 403)
        assert model.objects.count() == before

    def test_create_rejects_a_non_object_body(self, api_client, instance):
        if "create" not in self.operations or self.format != "json":
            return
        response = api_client(self.write_role).post(self.list_url(), [1, 2], format="json")
        assert_error_shape(response, 400)

    def test_update(self, api_client, instance, update_data):
        if "update" not in self.operations:
            response = api_client(self.write_role).patch(
                self.detail_url(instance), {}, format="json"
            )
            assert_error_shape(response, 405)
            return
        response = api_client(self.write_role).patch(
            self.detail_url(instance), update_data, format=self.format
        )
        assert response.status_code == 200, response.content
        instance.refresh_from_db()
        for field, value in update_data.items():
            stored = getattr(instance, field)
            assert getattr(stored, "pk", stored) == value
            assert response.json()[field] == value

    def test_update_refused_below_write_role(self, api_client, instance, update_data):
        if "update" not in self.operations:
            return
        response = api_client(lower_role(self.write_role)).patch(
            self.detail_url(instance), update_data, format=self.format
        )
        assert_error_shape(response, 403)
        before = {f: getattr(instance, f) for f in update_data}
        instance.refresh_from_db()
        assert {f: getattr(instance, f) for f in update_data} == before

    def test_delete(self, api_client, instance):
        if "delete" not in self.operations:
            assert_error_shape(api_client(self.write_role).delete(self.detail_url(instance)), 405)
            return
        response = api_client(self.write_role).delete(self.detail_url(instance))
        assert response.status_code == 204, response.content
        assert not self.model(instance).objects.filter(pk=instance.pk).exists()

    def test_delete_refused_below_write_role(self, api_client, instance):
        if "delete" not in self.operations:
            return
        response = api_client(lower_role(self.write_role)).delete(self.detail_url(instance))
        assert_error_shape(response, 403)
        assert self.model(instance).objects.filter(pk=instance.pk).exists()
