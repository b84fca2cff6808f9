"""A token request reads the account and its roles in one query, with the same answers
as before: the roles of every group, none for an inactive account or a wrong token."""

from django.contrib.auth.models import Group
from django.db import connection
from django.test.utils import CaptureQueriesContext
from rest_framework.test import APIClient

from common import roles

URL = "/api/test-events/"


def _client(user):
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {user.auth_token.key}")
    return client


def test_one_query_reads_the_token_its_user_and_groups(role_user):
    user = role_user(roles.VIEWER)
    with CaptureQueriesContext(connection) as captured:
        response = _client(user).get(URL)
    assert response.status_code == 200, response.content
    auth = [q["sql"] for q in captured.captured_queries if "auth_group" in q["sql"]]
    assert len(auth) == 1 and "authtoken_token" in auth[0], auth


def test_the_highest_of_several_groups_decides(role_user):
    user = role_user(roles.VIEWER)
    client = _client(user)
    assert client.post(URL, {"location": "x"}, format="json").status_code == 403
    user.groups.add(Group.objects.get(name=roles.OPERATOR))
    assert client.post(URL, {"location": "x"}, format="json").status_code == 201


def test_an_account_without_a_group_reads_nothing(role_user):
    assert _client(role_user(None)).get(URL).status_code == 403


def test_a_robot_in_the_operator_group_stays_a_robot(role_user):
    user = role_user(roles.OPERATOR)
    user.groups.add(Group.objects.get(name=roles.ROBOT))
    assert _client(user).get(URL).status_code == 403


def test_an_inactive_account_or_a_wrong_token_is_refused(role_user):
    user = role_user(roles.OPERATOR)
    user.is_active = False
    user.save()
    assert _client(user).get(URL).status_code == 401
    wrong = APIClient()
    wrong.credentials(HTTP_AUTHORIZATION="Token " + "0" * 40)
    assert wrong.get(URL).status_code == 401


def test_a_cached_token_costs_no_query_on_the_next_request(role_user):
    client = _client(role_user(roles.VIEWER))
    assert client.get(URL).status_code == 200
    with CaptureQueriesContext(connection) as captured:
        assert client.get(URL).status_code == 200
    assert not [q for q in captured.captured_queries if "authtoken_token" in q["sql"]]


def test_a_cached_token_is_revoked_at_once_by_the_changes_of_this_process(role_user):
    operator = role_user(roles.OPERATOR)
    client = _client(operator)
    assert client.post(URL, {"location": "x"}, format="json").status_code == 201
    operator.groups.remove(Group.objects.get(name=roles.OPERATOR))
    operator.groups.add(Group.objects.get(name=roles.VIEWER))
    assert client.post(URL, {"location": "y"}, format="json").status_code == 403

    viewer = role_user(roles.VIEWER)
    client = _client(viewer)
    assert client.get(URL).status_code == 200
    viewer.is_active = False
    viewer.save()
    assert client.get(URL).status_code == 401

    other = role_user(roles.VIEWER)
    client = _client(other)
    assert client.get(URL).status_code == 200
    other.auth_token.delete()
    assert client.get(URL).status_code == 401
