"""A directory account's role is asked of the directory again between sign-ins
(issue 47, item 7): a person taken out of the role groups, or put into the
deny group, loses the API token and the session; a changed role applies; a
hung directory ends nobody's access and holds no request."""

import json
import time

import pytest
import requests

from tests.support.directory import (
    DISABLED_GROUP,
    MARKS,
    PERSONS,
    ROLE_GROUPS,
    directory_server,
    sign_in,
    token_for,
)

pytestmark = MARKS

RECHECK_SECONDS = 1
# Enough for the busy test machine; the directory is asked every second.
WITHIN_S = 30


@pytest.fixture(scope="module")
def server(tmp_path_factory, directory):
    data_dir = tmp_path_factory.mktemp("directory-recheck-server")
    recheck = str(RECHECK_SECONDS)
    with directory_server(data_dir, directory, FTT_LDAP_RECHECK_SECONDS=recheck) as web:
        yield web


class Person:
    """A directory person signed in twice: a browser session and an API token."""

    def __init__(self, server, uid: str):
        self.server = server
        self.session, answer = sign_in(server, uid, PERSONS[uid][2])
        assert answer.status_code == 302, answer.text[:300]
        self.token = token_for(server, uid, PERSONS[uid][2]).json()["token"]

    def by_token(self, method: str = "get", path: str = "/api/vehicles/") -> requests.Response:
        headers = {"Authorization": f"Token {self.token}"}
        return requests.request(
            method, f"{self.server.url}{path}", headers=headers, json={}, timeout=30
        )

    def page(self) -> requests.Response:
        return self.session.get(f"{self.server.url}/", allow_redirects=False, timeout=30)

    def by_session(self, path: str) -> requests.Response:
        headers = {"X-CSRFToken": self.session.cookies["csrftoken"], "Referer": self.server.url}
        return self.session.post(f"{self.server.url}{path}", json={}, headers=headers, timeout=30)

    def may_write(self, answer: requests.Response) -> bool:
        # A new test event with every field left to its default: made for a
        # writer, 403 for a viewer.
        assert answer.status_code in (201, 403), answer.text[:300]
        return answer.status_code == 201


def tokens_and_roles(server, uid: str) -> dict:
    out = server.python(
        f"""
        import json
        from django.contrib.auth.models import User
        from rest_framework.authtoken.models import Token
        user = User.objects.get(username={uid!r})
        print(json.dumps({{
            "roles": sorted(user.groups.values_list("name", flat=True)),
            "staff": user.is_staff,
            "tokens": Token.objects.filter(user=user).count(),
        }}))
        """
    )
    return json.loads(out.strip().splitlines()[-1])


def until(condition, what: str):
    deadline = time.monotonic() + WITHIN_S
    while not (found := condition()):
        assert time.monotonic() < deadline, what
        time.sleep(0.2)
    return found


def test_a_person_taken_out_of_the_role_groups_loses_token_and_session_at_their_use(
    server, directory
):
    vera = Person(server, "vera")
    assert vera.by_token().status_code == 200
    assert vera.page().status_code == 200
    directory.move("vera", leave=[ROLE_GROUPS["viewer"]])
    until(lambda: vera.by_token().status_code == 401, "the token still works")
    until(lambda: vera.page().status_code == 302, "the session still works")
    assert "/login/" in vera.page().headers["Location"]
    assert tokens_and_roles(server, "vera") == {"roles": [], "staff": False, "tokens": 0}
    # Nor can she sign in again.
    _, answer = sign_in(server, "vera", PERSONS["vera"][2])
    assert answer.status_code == 200


def test_a_person_put_into_the_deny_group_is_ended_by_the_schedule_unused(server, directory):
    alma = Person(server, "alma")
    assert tokens_and_roles(server, "alma") == {
        "roles": ["administrator"],
        "staff": True,
        "tokens": 1,
    }
    directory.move("alma", join=[DISABLED_GROUP])
    # The worker's schedule, without any use of the token or the session.
    until(
        lambda: (
            "ended" in server.manage("ftt_directory_recheck")
            and tokens_and_roles(server, "alma")["tokens"] == 0
        ),
        "the schedule kept the token",
    )
    assert tokens_and_roles(server, "alma") == {"roles": [], "staff": False, "tokens": 0}
    assert alma.page().status_code == 302
    assert alma.by_token().status_code == 401


def test_a_person_moved_from_operator_to_viewer_can_no_longer_write(server, directory):
    otto = Person(server, "otto")
    assert otto.may_write(otto.by_token("post", "/api/test-events/"))
    assert otto.may_write(otto.by_session("/api/test-events/"))
    directory.move("otto", leave=[ROLE_GROUPS["operator"]])
    until(lambda: not otto.may_write(otto.by_token("post", "/api/test-events/")), "still writes")
    assert tokens_and_roles(server, "otto") == {"roles": ["viewer"], "staff": False, "tokens": 1}
    # Still signed in, as a viewer.
    assert not otto.may_write(otto.by_session("/api/test-events/"))
    assert otto.page().status_code == 200
    assert otto.by_token().status_code == 200


def test_a_hung_directory_ends_no_session_and_holds_no_request(server, directory):
    # "lena" is a directory administrator; this server has no local "lena".
    lena = Person(server, "lena")
    log = server.log_path.read_text
    directory.pause()
    try:
        slowest = 0.0

        def answered() -> bool:
            nonlocal slowest
            for ask in (lena.by_token, lena.page):
                start = time.monotonic()
                assert ask().status_code == 200
                slowest = max(slowest, time.monotonic() - start)
            return "did not answer a role check" in log()

        until(answered, "no role check was tried while the directory hung")
        # More checks fail the same way: logged once, each bounded by the 2 s timeout.
        for _ in range(10):
            answered()
        assert slowest < 10
        assert log().count("did not answer a role check") == 1
    finally:
        directory.resume()
    assert tokens_and_roles(server, "lena") == {
        "roles": ["administrator"],
        "staff": True,
        "tokens": 1,
    }
