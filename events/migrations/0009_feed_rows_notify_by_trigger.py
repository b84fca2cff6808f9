"""Every new feed row NOTIFYs the live readers from a trigger (PostgreSQL only).

The writers used to send NOTIFY themselves, one more round trip in every
transaction that announces something, most of all in a single stored pose.
PostgreSQL delivers a transaction's notifications at its commit, drops those
of a rolled-back savepoint and folds repeats into one, as before.  The channel
is events.feed.CHANNEL, written out here so that the migration stays as it is
whatever the code later says.
"""

from django.db import migrations

from common.sql import postgresql_only

FORWARD = """
CREATE FUNCTION ftt_live_notify() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
    PERFORM pg_notify('ftt_live', '');
    RETURN NULL;
END $$;
CREATE TRIGGER ftt_live_notify AFTER INSERT ON rosbridge_app_announcement
    FOR EACH ROW EXECUTE FUNCTION ftt_live_notify();
"""

BACKWARD = """
DROP TRIGGER IF EXISTS ftt_live_notify ON rosbridge_app_announcement;
DROP FUNCTION IF EXISTS ftt_live_notify();
"""


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0008_itoreason_quick"),
    ]

    operations = [postgresql_only(FORWARD, BACKWARD)]
