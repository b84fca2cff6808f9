"""SQL for a least-privilege PostGIS role that ``ftt_collect`` on a robot can use.

    manage.py ftt_robot_role ftt_robot                 print the SQL
    manage.py ftt_robot_role ftt_robot --apply         run it (as the owner)

The role reads the logbook and the catalogues, writes segments, telemetry, the
change feed and its collector's status and commands, and has no access at all
to accounts, sessions, tokens, login attempts or the admin log: a lost robot
exposes none of them.  Give it a password (``ALTER ROLE ... PASSWORD``) and put
it into the robot's FTT_DATABASE_URL.
"""

import re

from django.apps import apps
from django.core.management.base import BaseCommand, CommandError
from django.db import connection
from django.utils.translation import gettext as _

# Read: the logbook and configuration the collector looks up.
READ_APPS = ("events", "telemetry", "rosbridge_app")
# Written by the collector's recording path.
WRITE_APPS = ("telemetry", "rosbridge_app")
# A segment's change history is written beside it (events.models.changes).
WRITE_TABLES = ("events_segment", "events_historicalsegment", "rosbridge_app_announcement")
# Row locks only (SELECT ... FOR UPDATE needs UPDATE): the services lock the
# leg and shift they write under, so that closing one waits for the write.
LOCK_TABLES = ("events_leg", "events_shift", "events_testevent")
ROLE_NAME = re.compile(r"[a-z_][a-z0-9_]{0,62}")


def tables(app_labels) -> list[str]:
    return sorted(
        {
            model._meta.db_table
            for label in app_labels
            for model in apps.get_app_config(label).get_models(include_auto_created=True)
        }
    )


def grant_statements(role: str) -> list[str]:
    name = connection.ops.quote_name(role)
    read = tables(READ_APPS) + ["spatial_ref_sys", "django_content_type"]
    write = sorted(set(tables(WRITE_APPS)) | set(WRITE_TABLES))
    quoted = connection.ops.quote_name
    return [
        f"DO $$ BEGIN IF NOT EXISTS (SELECT FROM pg_roles WHERE rolname = '{role}') "
        f"THEN CREATE ROLE {name} LOGIN; END IF; END $$",
        f"REVOKE ALL ON ALL TABLES IN SCHEMA public FROM {name}",
        f"GRANT USAGE ON SCHEMA public TO {name}",
        *(f"GRANT SELECT ON {quoted(t)} TO {name}" for t in read),
        *(f"GRANT INSERT, UPDATE, DELETE ON {quoted(t)} TO {name}" for t in write),
        *(f"GRANT UPDATE ON {quoted(t)} TO {name}" for t in LOCK_TABLES),
        f"GRANT USAGE ON ALL SEQUENCES IN SCHEMA public TO {name}",
    ]


class Command(BaseCommand):
    help = _("Print (or apply) the SQL for a least-privilege PostGIS role for ftt_collect.")

    def add_arguments(self, parser):
        parser.add_argument("role", help=_("Name of the database role, e.g. ftt_robot."))
        parser.add_argument("--apply", action="store_true", help=_("Run the SQL now."))

    def handle(self, *args, role, apply, **options):
        if connection.vendor != "postgresql":
            raise CommandError(_("Robot roles are for PostGIS; SpatiaLite has no roles."))
        if not ROLE_NAME.fullmatch(role):
            raise CommandError(_("A role name is lower-case letters, digits and _ (at most 63)."))
        statements = grant_statements(role)
        with connection.cursor() as cursor:
            if apply:
                for statement in statements:
                    cursor.execute(statement)
        for statement in statements:
            self.stdout.write(statement + ";")
