"""Sign-in from a real OpenLDAP directory, on the production server as README configures it."""

import json
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
import requests

from tests.support.directory import (
    MARKS,
    PERSONS,
    directory_server,
    sign_in,
    token_for,
)

pytestmark = MARKS


@pytest.fixture(scope="module")
def server(tmp_path_factory, directory):
    data_dir = tmp_path_factory.mktemp("directory-server")
    with directory_server(data_dir, directory, FTT_LOGIN_FAILURE_LIMIT="3") as web:
        yield web


def account(server, username: str) -> dict | None:
    out = server.python(
        f"""
        import json
        from django.contrib.auth.models import User
        user = User.objects.filter(username={username!r}).first()
        print(json.dumps(user and {{
            "groups": sorted(user.groups.values_list("name", flat=True)),
            "staff": user.is_staff, "email": user.email, "name": user.get_full_name(),
            "superuser": user.is_superuser,
        }}))
        """
    )
    return json.loads(out.strip().splitlines()[-1])


def test_a_directory_operator_signs_in_and_gets_the_operator_role(server):
    session, answer = sign_in(server, "otto", PERSONS["otto"][2])
    assert answer.status_code == 302, answer.text[:500]
    assert session.get(f"{server.url}/", timeout=10).status_code == 200
    assert account(server, "otto") == {
        "groups": ["operator"],
        "staff": False,
        "superuser": False,
        "email": "otto@ftt.test",
        "name": "Otto Operator",
    }


def test_a_directory_administrator_may_open_the_admin(server):
    session, answer = sign_in(server, "alma", PERSONS["alma"][2])
    assert answer.status_code == 302
    assert session.get(f"{server.url}/admin/", timeout=10).status_code == 200
    assert account(server, "alma")["groups"] == ["administrator"]


@pytest.mark.parametrize("uid", ["nora", "dora"])
def test_a_person_without_a_role_group_or_in_the_deny_group_is_refused(server, uid):
    _, answer = sign_in(server, uid, PERSONS[uid][2])
    assert answer.status_code == 200
    assert "The user name or password is not right" in answer.text
    assert account(server, uid) is None


def test_a_local_account_still_signs_in_beside_the_directory(server):
    _, answer = sign_in(server, "admin", "local-admin-pw-1")
    assert answer.status_code == 302


def test_guessing_a_directory_password_is_throttled(server, fresh_address):
    for _ in range(2):
        _, answer = sign_in(server, "vera", "wrong-password")
        assert answer.status_code == 200
    _, answer = sign_in(server, "vera", "wrong-password")
    assert answer.status_code == 429
    _, answer = sign_in(server, "vera", PERSONS["vera"][2])
    assert answer.status_code == 429
    assert int(answer.headers["Retry-After"]) > 0
    assert account(server, "vera") is None


@pytest.fixture(scope="module")
def local_accounts(server):
    """FTT's own accounts whose names the directory also has: the superuser
    (made by ftt_ensure_admin), a local viewer and a robot; their tokens."""
    out = server.python(
        """
        import json
        from django.contrib.auth.models import Group, User
        from rest_framework.authtoken.models import Token
        from events.models import Vehicle
        lena = User.objects.create_user("lena", password="lena-local-pw-1")
        lena.groups.add(Group.objects.get(name="viewer"))
        Vehicle.objects.create(key="rover", short_description="Rover")
        admin = User.objects.get(username="admin")
        print(json.dumps({"admin": Token.objects.get_or_create(user=admin)[0].key}))
        """
    )
    tokens = json.loads(out.strip().splitlines()[-1])
    tokens["robot-a"] = server.manage("ftt_robot_account", "robot-a", "--vehicle", "rover").strip()
    return tokens


@pytest.fixture
def fresh_address(server):
    """The failures of earlier tests no longer count against 127.0.0.1."""
    server.manage("axes_reset")


@pytest.mark.parametrize("uid", ["admin", "lena", "robot-a"])
def test_a_directory_person_never_signs_in_as_the_local_account_of_that_name(
    server, local_accounts, fresh_address, uid
):
    before = account(server, uid)
    _, answer = sign_in(server, uid, PERSONS[uid][2])
    assert answer.status_code == 200
    assert "The user name or password is not right" in answer.text
    token = token_for(server, uid, PERSONS[uid][2])
    assert token.status_code == 400
    assert "token" not in token.json()
    # The local account is as it was: no name, mail, role or staff flag from the directory.
    assert account(server, uid) == before
    assert before["name"] == ""


def test_the_directory_namesake_of_the_superuser_gets_none_of_its_rights(
    server, local_accounts, fresh_address
):
    session, _ = sign_in(server, "admin", PERSONS["admin"][2])
    assert session.get(f"{server.url}/admin/", allow_redirects=False, timeout=10).status_code == 302
    assert account(server, "admin")["staff"] and account(server, "admin")["superuser"]
    # The local superuser still signs in, and its token still works.
    _, answer = sign_in(server, "admin", "local-admin-pw-1")
    assert answer.status_code == 302
    mine = {"Authorization": f"Token {local_accounts['admin']}"}
    assert requests.get(f"{server.url}/api/vehicles/", headers=mine, timeout=10).status_code == 200
    assert token_for(server, "admin", "local-admin-pw-1").json()["token"] == local_accounts["admin"]


def test_local_accounts_sign_in_with_their_own_passwords_beside_the_directory(
    server, local_accounts, fresh_address
):
    _, answer = sign_in(server, "lena", "lena-local-pw-1")
    assert answer.status_code == 302
    assert account(server, "lena")["groups"] == ["viewer"]


def robot_answers(server, token: str) -> requests.Response:
    """The original robot node's question (no leg is open: it is told so)."""
    return requests.get(f"{server.url}/legacy/{token}/robot_state", timeout=10)


def test_a_hung_directory_holds_no_sign_in_and_no_robot(server, directory, local_accounts):
    server.manage("axes_reset")
    directory.pause()
    try:
        with ThreadPoolExecutor(8) as pool:
            start = time.monotonic()
            waiting = [pool.submit(sign_in, server, "otto", PERSONS["otto"][2]) for _ in range(8)]
            # While those wait for the directory: a local account signs in, a robot is answered.
            _, local = sign_in(server, "admin", "local-admin-pw-1")
            assert local.status_code == 302
            robot = robot_answers(server, local_accounts["robot-a"])
            assert robot.status_code < 500 and "[" in robot.text
            answers = [future.result()[1] for future in waiting]
            # Within the 2 s directory timeout, with time to spare for the busy machine.
            assert time.monotonic() - start < 15
        for answer in answers:
            assert answer.status_code == 503
            assert "The directory cannot be reached" in answer.text
            assert int(answer.headers["Retry-After"]) > 0
        # Not counted as failed sign-ins: with a limit of 3, more of them are not a lockout.
        for _ in range(3):
            _, again = sign_in(server, "alma", PERSONS["alma"][2])
            assert again.status_code == 503
    finally:
        directory.resume()
    deadline = time.monotonic() + 20
    while True:
        session, answer = sign_in(server, "otto", PERSONS["otto"][2])
        if answer.status_code != 503 or time.monotonic() > deadline:
            break
        time.sleep(0.5)
    assert answer.status_code == 302
