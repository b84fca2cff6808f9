"""The feed's table has no NOTIFY trigger: the writer's process wakes the
live readers after its commit (live.wakeup), on every database."""

from django.db import migrations

from common.sql import postgresql_only

FORWARD = """
DROP TRIGGER IF EXISTS ftt_live_notify ON rosbridge_app_announcement;
DROP FUNCTION IF EXISTS ftt_live_notify();
"""

# As migration 0010 left it.
BACKWARD = """
CREATE FUNCTION ftt_live_notify() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
    IF coalesce(current_setting('ftt.notify_later', true), '') <> 'on' THEN
        PERFORM pg_notify('ftt_live', '');
    END IF;
    RETURN NULL;
END $$;
CREATE TRIGGER ftt_live_notify AFTER INSERT ON rosbridge_app_announcement
    FOR EACH ROW EXECUTE FUNCTION ftt_live_notify();
"""


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0010_single_poses_notify_later"),
    ]

    operations = [postgresql_only(FORWARD, BACKWARD)]
