"""``manage.py ftt_prepare``: what scripts/run.sh does before serving, in one
process: the system checks, the migrations only when some are not applied
yet, and ``ftt_ensure_admin``.

The checks run once, and not at all while neither the code, the locked
libraries nor the ``FTT_*`` settings changed since they last passed on this
installation (the stamp ``<data dir>/.ftt-checked``); ``--check`` runs them
anyway. The README's Quick start gives the start-up times.
"""

import hashlib
import os
import sys
from pathlib import Path

from django.conf import settings
from django.core.management import call_command
from django.core.management.base import BaseCommand
from django.db import connection
from django.db.migrations.executor import MigrationExecutor
from django.utils.translation import gettext as _

ROOT = Path(settings.BASE_DIR)
STAMP = ".ftt-checked"


def missing_migrations() -> list:
    """The migrations the database has not applied, in order."""
    executor = MigrationExecutor(connection)
    return executor.migration_plan(executor.loader.graph.leaf_nodes())


def checked_digest() -> str:
    """What the system checks' outcome follows from: FTT's code, the locked
    libraries, the interpreter and the settings from the environment."""
    digest = hashlib.sha256(sys.version.encode())
    apps = sorted(path.parent for path in ROOT.glob("*/apps.py"))
    for path in sorted(p for app in apps for p in app.rglob("*.py")):
        digest.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes())
    if (ROOT / "requirements.txt").exists():
        digest.update((ROOT / "requirements.txt").read_bytes())
    for key in sorted(os.environ):
        if key.startswith(("FTT_", "DJANGO_")):
            digest.update(f"{key}={os.environ[key]}\0".encode())
    return digest.hexdigest()


class Command(BaseCommand):
    help = _("Check, migrate what is missing and ensure the administrator account, before serving.")
    # Run below, only when their outcome may have changed.
    requires_system_checks = []

    def add_arguments(self, parser):
        parser.add_argument(
            "--check", action="store_true", help=_("Run the system checks even if nothing changed.")
        )

    def handle(self, *args, **options):
        verbosity = options["verbosity"]
        stamp = Path(settings.DATA_DIR) / STAMP
        digest = checked_digest()
        if options["check"] or not stamp.exists() or stamp.read_text() != digest:
            self.check(databases=[connection.alias])
            stamp.parent.mkdir(parents=True, exist_ok=True)
            stamp.write_text(digest)
        else:
            self.stdout.write(_("System checks: nothing changed since they last passed."))
        if missing_migrations():
            call_command("migrate", interactive=False, verbosity=verbosity, skip_checks=True)
        else:
            self.stdout.write(_("Migrations: all applied, none to run."))
        call_command("ftt_ensure_admin", verbosity=verbosity, stdout=self.stdout)
