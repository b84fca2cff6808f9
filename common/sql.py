"""PostgreSQL connections of FTT's own and migration steps of raw SQL."""

from django.db import connections, migrations
from psycopg.conninfo import make_conninfo


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
