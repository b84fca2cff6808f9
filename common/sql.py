"""Raw SQL on PostgreSQL beyond what Django's cursors offer."""

import psycopg
from django.db import connection


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
