"""The migrated databases every xdist worker's test database is copied from.

pytest-django makes each worker's test database and migrates it: the whole
chain of migrations once per worker. Instead one worker migrates a template,
named by the digest of the code that migrations can run: on PostgreSQL Django
creates every test database as a copy of it (``TEST["TEMPLATE"]``); on the
embedded database the file is copied into place and kept (keepdb). Either
way Django's migrate then finds nothing to do.
"""

import tempfile
import uuid
from pathlib import Path

import psycopg
from django.conf import settings

from tests.support.sites import Site, code_digest, copy_sqlite, migrated_template

_LOCK = 4_112_026  # any number the server's other users do not lock
_KEPT_TEMPLATES = 8


def use_migrated_template() -> None:
    """Points this process's test database at the migrated template, making the
    template first when no process has."""
    name = migrated_postgres_template()
    if name:
        settings.DATABASES["default"].setdefault("TEST", {})["TEMPLATE"] = name


def migrated_postgres_template() -> str:
    """The name of the PostgreSQL database migrated by this code, made when missing
    (one process at a time, under an advisory lock); "" on the embedded database."""
    db = settings.DATABASES["default"]
    if db["ENGINE"] != "django.contrib.gis.db.backends.postgis":
        return ""
    name = f"ftt_template_{code_digest()}"
    server = _server()
    with psycopg.connect(**server, dbname="postgres", autocommit=True) as conn:
        conn.execute("SELECT pg_advisory_lock(%s)", (_LOCK,))
        try:
            found = conn.execute("SELECT 1 FROM pg_database WHERE datname = %s", (name,))
            if found.fetchone() is None:
                _make_template(conn, server, name)
        finally:
            conn.execute("SELECT pg_advisory_unlock(%s)", (_LOCK,))
    return name


def older_database(tree: Path, rev: str) -> str:
    """The URL of a new PostgreSQL database as the FTT in ``tree`` (commit ``rev``)
    migrates it: a copy of a template that the first call on a server makes with
    that code's migrate (one process at a time).  drop_database removes it."""
    server = _server()
    template = f"ftt_older_{rev}"
    name = f"{template}_{uuid.uuid4().hex[:8]}"
    with psycopg.connect(**server, dbname="postgres", autocommit=True) as conn:
        conn.execute("SELECT pg_advisory_lock(%s)", (_LOCK,))
        try:
            found = conn.execute("SELECT 1 FROM pg_database WHERE datname = %s", (template,))
            if found.fetchone() is None:
                building = f"{template}_building"
                conn.execute(f'DROP DATABASE IF EXISTS "{building}" WITH (FORCE)')
                conn.execute(f'CREATE DATABASE "{building}"')
                Site(
                    tempfile.mkdtemp(prefix="ftt-older-"),
                    root=tree,
                    FTT_DATABASE_URL=_url(server, building),
                ).manage("migrate", "--noinput", "-v", "0")
                conn.execute(f'ALTER DATABASE "{building}" RENAME TO "{template}"')
            conn.execute(f'CREATE DATABASE "{name}" TEMPLATE "{template}"')
        finally:
            conn.execute("SELECT pg_advisory_unlock(%s)", (_LOCK,))
    return _url(server, name)


def drop_database(url: str) -> None:
    with psycopg.connect(**_server(), dbname="postgres", autocommit=True) as conn:
        conn.execute(f'DROP DATABASE IF EXISTS "{url.rsplit("/", 1)[1]}" WITH (FORCE)')


def _server() -> dict:
    db = settings.DATABASES["default"]
    return {
        "host": db["HOST"] or "127.0.0.1",
        "port": db["PORT"] or 5432,
        "user": db["USER"],
        "password": db["PASSWORD"],
    }


def _url(server: dict, name: str) -> str:
    return (
        f"postgis://{server['user']}:{server['password']}@{server['host']}:{server['port']}/{name}"
    )


def _make_template(conn, server: dict, name: str) -> None:
    # Templates of earlier code are of no use any more, but another checkout's
    # suite on the same server may still be copying one: the newest few stay.
    stale = conn.execute(
        "SELECT datname FROM pg_database WHERE datname LIKE 'ftt\\_template\\_%%'"
        " ORDER BY oid DESC OFFSET %s",
        (_KEPT_TEMPLATES,),
    )
    for (old,) in stale.fetchall():
        conn.execute(f'DROP DATABASE "{old}" WITH (FORCE)')
    building = f"{name}_building"
    conn.execute(f'CREATE DATABASE "{building}"')
    url = _url(server, building)
    Site(tempfile.mkdtemp(prefix="ftt-template-"), FTT_DATABASE_URL=url).manage(
        "migrate", "--noinput", "-v", "0"
    )
    conn.execute(f'ALTER DATABASE "{building}" RENAME TO "{name}"')


def place_migrated_embedded_database() -> bool:
    """Copies the migrated embedded database to where this worker's test database
    goes (its name has the xdist suffix by now); True when it did."""
    db = settings.DATABASES["default"]
    if db["ENGINE"] != "ftt_site.db_spatialite":
        return False
    copy_sqlite(migrated_template(), Path(db["TEST"]["NAME"]))
    return True
