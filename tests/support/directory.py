"""A real OpenLDAP server (Debian's slapd) on loopback with a small directory."""

import os
import re
import shutil
import signal
import subprocess
import textwrap
import time
from contextlib import contextmanager
from pathlib import Path

import ldap
import pytest
import requests
from ldap import modlist

from tests.support.sites import copy_migrated_database
from tests.support.web import WebServer, free_port

BASE = "dc=ftt,dc=test"
ADMIN_DN = f"cn=admin,{BASE}"
ADMIN_PASSWORD = "directory-admin-pw"
PEOPLE = f"ou=people,{BASE}"
GROUPS = f"ou=groups,{BASE}"
ROLE_GROUPS = {
    "viewer": f"cn=ftt-viewers,{GROUPS}",
    "operator": f"cn=ftt-operators,{GROUPS}",
    "administrator": f"cn=ftt-administrators,{GROUPS}",
}
DISABLED_GROUP = f"cn=disabled,{GROUPS}"
# uid: (given name, surname, password, groups)
PERSONS = {
    "vera": ("Vera", "Viewer", "vera-pw-1", [ROLE_GROUPS["viewer"]]),
    "otto": ("Otto", "Operator", "otto-pw-1", [ROLE_GROUPS["viewer"], ROLE_GROUPS["operator"]]),
    "alma": ("Alma", "Admin", "alma-pw-1", [ROLE_GROUPS["administrator"]]),
    "nora": ("Nora", "Nogroup", "nora-pw-1", []),
    "dora": ("Dora", "Disabled", "dora-pw-1", [ROLE_GROUPS["operator"], DISABLED_GROUP]),
    # Directory people named like FTT's local accounts (the superuser, a local
    # viewer, a robot): the directory must never sign them in as those.
    "admin": ("Adam", "Namesake", "adam-pw-1", [ROLE_GROUPS["viewer"]]),
    "lena": ("Lena", "Namesake", "lena-dir-pw-1", [ROLE_GROUPS["administrator"]]),
    "robot-a": ("Robert", "Namesake", "robert-pw-1", [ROLE_GROUPS["operator"]]),
}


def slapd_available() -> bool:
    return shutil.which("slapd") is not None or Path("/usr/sbin/slapd").exists()


# A directory test module's marks: a server of its own on the embedded database.
MARKS = [
    pytest.mark.spatialite,
    pytest.mark.skipif(not slapd_available(), reason="needs Debian's slapd"),
]


def person_dn(uid: str) -> str:
    return f"uid={uid},{PEOPLE}"


class Directory:
    def __init__(self, folder: Path):
        self.folder = folder
        self.port = free_port()
        self.uri = f"ldap://127.0.0.1:{self.port}/"
        self.process = None

    def environment(self) -> dict[str, str]:
        """FTT's settings for this directory, as an administrator would set them."""
        return {
            "FTT_LDAP_SERVER_URI": self.uri,
            "FTT_LDAP_BIND_DN": ADMIN_DN,
            "FTT_LDAP_BIND_PASSWORD": ADMIN_PASSWORD,
            "FTT_LDAP_USER_BASE": PEOPLE,
            "FTT_LDAP_GROUP_BASE": GROUPS,
            "FTT_LDAP_VIEWER_GROUP": ROLE_GROUPS["viewer"],
            "FTT_LDAP_OPERATOR_GROUP": ROLE_GROUPS["operator"],
            "FTT_LDAP_ADMINISTRATOR_GROUP": ROLE_GROUPS["administrator"],
            "FTT_LDAP_DENY_GROUP": DISABLED_GROUP,
        }

    def start(self) -> "Directory":
        (self.folder / "db").mkdir(parents=True)
        config = self.folder / "slapd.conf"
        config.write_text(
            textwrap.dedent(
                f"""\
                include /etc/ldap/schema/core.schema
                include /etc/ldap/schema/cosine.schema
                include /etc/ldap/schema/inetorgperson.schema
                include /etc/ldap/schema/nis.schema
                modulepath /usr/lib/ldap
                moduleload back_mdb
                pidfile {self.folder}/slapd.pid
                database mdb
                suffix "{BASE}"
                rootdn "{ADMIN_DN}"
                rootpw {ADMIN_PASSWORD}
                directory {self.folder}/db
                """
            )
        )
        log = open(self.folder / "slapd.log", "w")  # noqa: SIM115 - open while it runs
        self.process = subprocess.Popen(
            ["slapd", "-f", str(config), "-h", self.uri, "-d", "0"],
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        self._fill(self._admin_connection())
        return self

    def _admin_connection(self):
        deadline = time.monotonic() + 20
        while True:
            connection = ldap.initialize(self.uri)
            try:
                connection.simple_bind_s(ADMIN_DN, ADMIN_PASSWORD)
                return connection
            except ldap.SERVER_DOWN:
                if self.process.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError((self.folder / "slapd.log").read_text()[-2000:]) from None
                time.sleep(0.1)

    def _fill(self, connection) -> None:
        def add(dn, **attributes):
            encoded = {
                key: [v.encode() for v in (value if isinstance(value, list) else [value])]
                for key, value in attributes.items()
            }
            connection.add_s(dn, modlist.addModlist(encoded))

        add(BASE, objectClass=["dcObject", "organization"], dc="ftt", o="FTT test")
        add(PEOPLE, objectClass="organizationalUnit", ou="people")
        add(GROUPS, objectClass="organizationalUnit", ou="groups")
        members: dict[str, list[str]] = {dn: [] for dn in [*ROLE_GROUPS.values(), DISABLED_GROUP]}
        for uid, (given, surname, password, groups) in PERSONS.items():
            add(
                person_dn(uid),
                objectClass="inetOrgPerson",
                uid=uid,
                cn=f"{given} {surname}",
                givenName=given,
                sn=surname,
                mail=f"{uid}@ftt.test",
                userPassword=password,
            )
            for group in groups:
                members[group].append(person_dn(uid))
        for dn, people in members.items():
            # groupOfNames needs a member: the admin stands in for an empty group.
            add(
                dn,
                objectClass="groupOfNames",
                cn=dn.split(",")[0][3:],
                member=people or [ADMIN_DN],
            )
        connection.unbind_s()

    def move(self, uid: str, leave: list[str] = (), join: list[str] = ()) -> None:
        """Takes a person out of groups and into others, as the directory's
        administrator would."""
        connection = self._admin_connection()
        member = [person_dn(uid).encode()]
        for group in leave:
            connection.modify_s(group, [(ldap.MOD_DELETE, "member", member)])
        for group in join:
            connection.modify_s(group, [(ldap.MOD_ADD, "member", member)])
        connection.unbind_s()

    def pause(self) -> None:
        """SIGSTOP: the server keeps its socket, so connections open and hang."""
        self.process.send_signal(signal.SIGSTOP)

    def resume(self) -> None:
        self.process.send_signal(signal.SIGCONT)

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.resume()
            self.process.terminate()
            self.process.wait(10)


def sign_in(server, username: str, password: str) -> tuple[requests.Session, requests.Response]:
    """The sign-in page's form, as a browser sends it."""
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


def token_for(server, username: str, password: str) -> requests.Response:
    return requests.post(
        f"{server.url}/api/token/", data={"username": username, "password": password}, timeout=30
    )


@contextmanager
def running_directory(folder: Path):
    found = Directory(folder).start()
    try:
        yield found
    finally:
        found.stop()


@contextmanager
def directory_server(data_dir: Path, directory: Directory, **env: str):
    """FTT's production server on the embedded database, signing in from
    ``directory`` as README configures it, with the superuser ``admin``."""
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    env = {
        "FTT_DATA_DIR": str(data_dir),
        "FTT_ADMIN_PASSWORD": "local-admin-pw-1",
        "FTT_LDAP_TIMEOUT": "2",
        **env,
        **directory.environment(),
    }
    copy_migrated_database(data_dir)
    web = WebServer(env, workers=1, log=data_dir / "server.log")
    web.manage("ftt_ensure_admin")
    try:
        yield web.start(migrate=False)
    finally:
        web.stop()
