"""A database that is busy is the server's state: 503 with Retry-After, never 400 or 500."""

import sqlite3
from contextlib import contextmanager

import pytest
from django.db import connection
from psycopg import connect as pg_connect

from events.models import Note
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db(transaction=True)


@pytest.fixture
def master(leg):
    # Made before the lock is taken: only the note write meets it.
    return start_auto(leg)


@contextmanager
def writers_blocked():
    """Another client holds the write lock; FTT's connection gives up after 0.2 s."""
    connection.ensure_connection()
    if connection.vendor == "sqlite":
        connection.connection.execute("PRAGMA busy_timeout = 200")
        other = sqlite3.connect(connection.settings_dict["NAME"], isolation_level=None)
        other.execute("BEGIN IMMEDIATE")
        try:
            yield
        finally:
            other.execute("ROLLBACK")
            other.close()
            connection.connection.execute("PRAGMA busy_timeout = 30000")
        return
    with connection.cursor() as cursor:
        cursor.execute("SET lock_timeout = '200ms'")
    params = connection.get_connection_params()
    keys = ("host", "port", "user", "password", "dbname")
    try:
        with pg_connect(**{k: params[k] for k in keys if params.get(k)}) as other:
            other.execute(f"LOCK TABLE {Note._meta.db_table} IN ACCESS EXCLUSIVE MODE")
            yield
            other.rollback()
    finally:
        with connection.cursor() as cursor:
            cursor.execute("SET lock_timeout = 0")


def test_a_write_while_the_database_is_locked_is_refused_with_503_and_kept_nowhere(
    api_client, master
):
    client = api_client()
    with writers_blocked():
        response = client.post(
            "/api/notes/", {"segment": master.pk, "text": "while locked"}, format="json"
        )
    assert response.status_code == 503, response.content
    assert int(response.headers["Retry-After"]) > 0
    assert "busy" in response.json()["detail"]
    assert not Note.objects.filter(text="while locked").exists()


def test_the_same_write_succeeds_without_the_lock(api_client, master):
    response = api_client().post(
        "/api/notes/", {"segment": master.pk, "text": "after"}, format="json"
    )
    assert response.status_code == 201, response.content
    assert Note.objects.filter(text="after").count() == 1
