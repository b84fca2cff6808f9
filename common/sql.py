"""Raw SQL on PostgreSQL beyond what Django's cursors offer."""

import psycopg
from django.core.exceptions import EmptyResultSet
from django.db import connection, connections, migrations
from psycopg.conninfo import make_conninfo


def bound_cursor(*, binary_results: bool = False):
    """A cursor on Django's connection (same transaction, logged and counted like
    Django's own) that sends its parameters apart from the SQL text.

    Django binds parameters into the text on the client, which rules out
    binary parameters (``%b``: psycopg packs a list of floats or uuids in C)
    and binary results (bytes as stored, not hex text to decode).
    """
    connection.ensure_connection()
    raw = psycopg.Cursor(connection.connection)
    if binary_results:
        raw.format = psycopg.pq.Format.BINARY
    wrap = connection.make_debug_cursor if connection.queries_logged else connection.make_cursor
    return wrap(raw)


def plain_rows(queryset) -> list[tuple]:
    """The rows of a ``values_list`` queryset of plain columns (numbers, text,
    timestamps), as ``list(queryset)`` gives them.

    On PostgreSQL they are loaded in binary: psycopg reads a timestamp in C,
    where Django parses its text in Python (docs/report.md has the figures).
    Elsewhere Django reads them.
    """
    if queryset.query.annotation_select:
        raise ValueError("plain_rows reads columns, not annotations")
    if connection.vendor != "postgresql":
        return list(queryset)
    compiler = queryset.query.get_compiler(connection=connection)
    try:
        sql, params = compiler.as_sql()
    except EmptyResultSet:  # a filter that can match nothing (pk__in=[])
        return []
    if compiler.get_converters([column for column, _sql, _alias in compiler.select]):
        raise ValueError("plain_rows reads plain columns, not fields Django converts")
    with bound_cursor(binary_results=True) as cursor:
        cursor.execute(sql, params)
        return cursor.fetchall()


def conninfo(using: str = "default") -> str:
    """A connection string to the database Django uses, for a connection of its
    own (a LISTEN, a NOTIFY outside the request's transaction)."""
    db = connections[using].settings_dict
    return make_conninfo(
        dbname=db["NAME"],
        user=db.get("USER") or None,
        password=db.get("PASSWORD") or None,
        host=db.get("HOST") or None,
        port=db.get("PORT") or None,
    )


def postgresql_only(forward: str, backward: str) -> migrations.RunPython:
    """A migration step of raw SQL that runs on PostgreSQL and nowhere else."""

    def run(sql):
        def step(apps, schema_editor):
            if schema_editor.connection.vendor == "postgresql":
                schema_editor.execute(sql)

        return step

    return migrations.RunPython(run(forward), run(backward))
