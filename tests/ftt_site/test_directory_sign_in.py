"""Sign-in from a real OpenLDAP directory, on the production server as README configures it."""

import json
import os
import re

import pytest
import requests

from tests.support.directory import PERSONS, Directory, slapd_available
from tests.support.web import WebServer

# On SpatiaLite only: drives a server of its own on the embedded database.
pytestmark = [
    pytest.mark.spatialite,
    pytest.mark.skipif(not slapd_available(), reason="needs Debian's slapd"),
]


@pytest.fixture(scope="module")
def directory(tmp_path_factory):
    found = Directory(tmp_path_factory.mktemp("directory")).start()
    yield found
    found.stop()


@pytest.fixture(scope="module")
def server(tmp_path_factory, directory):
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    data_dir = tmp_path_factory.mktemp("directory-server")
    env = {
        "FTT_DATA_DIR": str(data_dir),
        "FTT_ADMIN_PASSWORD": "local-admin-pw-1",
        "FTT_LOGIN_FAILURE_LIMIT": "3",
        **directory.environment(),
    }
    web = WebServer(env, workers=1, log=data_dir / "server.log")
    web.manage("migrate", "--noinput")
    web.manage("ftt_ensure_admin")
    yield web.start(migrate=False)
    web.stop()


def sign_in(server, username: str, password: str) -> tuple[requests.Session, requests.Response]:
    session = requests.Session()
    page = session.get(f"{server.url}/login/", timeout=10)
    token = re.search(r'name="csrfmiddlewaretoken" value="([^"]+)"', page.text).group(1)
    answer = session.post(
        f"{server.url}/login/",
        data={"username": username, "password": password, "csrfmiddlewaretoken": token},
        headers={"Referer": f"{server.url}/login/"},
        allow_redirects=False,
        timeout=30,
    )
    return session, answer


def account(server, username: str) -> dict | None:
    out = server.python(
        f"""
        import json
        from django.contrib.auth.models import User
        user = User.objects.filter(username={username!r}).first()
        print(json.dumps(user and {{
            "groups": sorted(user.groups.values_list("name", flat=True)),
            "staff": user.is_staff, "email": user.email, "name": user.get_full_name(),
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


def test_guessing_a_directory_password_is_throttled(server):
    for _ in range(2):
        _, answer = sign_in(server, "vera", "wrong-password")
        assert answer.status_code == 200
    _, answer = sign_in(server, "vera", "wrong-password")
    assert answer.status_code == 429
    _, answer = sign_in(server, "vera", PERSONS["vera"][2])
    assert answer.status_code == 429
    assert int(answer.headers["Retry-After"]) > 0
    assert account(server, "vera") is None
