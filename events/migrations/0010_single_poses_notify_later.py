"""The feed's trigger leaves the NOTIFY to the writer when it says it sends one later.

PostgreSQL holds a database-wide lock from a notifying transaction's commit
until its WAL flush ends, so commits that notify never share a flush: a
stream of single poses, each its own commit, was bounded by it.  The
statement storing a single pose therefore sets ``ftt.notify_later`` for its
own transaction, and its process sends one NOTIFY for many such commits just
after them (events.notifier).  Every other writer notifies from the trigger
as before.  The setting's name is events.notifier.LATER, written out here so
that the migration stays as it is whatever the code later says.
"""

from django.db import migrations

from common.sql import postgresql_only

FORWARD = """
CREATE OR REPLACE FUNCTION ftt_live_notify() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
    IF coalesce(current_setting('ftt.notify_later', true), '') <> 'on' THEN
        PERFORM pg_notify('ftt_live', '');
    END IF;
    RETURN NULL;
END $$;
"""

BACKWARD = """
CREATE OR REPLACE FUNCTION ftt_live_notify() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
    PERFORM pg_notify('ftt_live', '');
    RETURN NULL;
END $$;
"""


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0009_feed_rows_notify_by_trigger"),
    ]

    operations = [postgresql_only(FORWARD, BACKWARD)]
