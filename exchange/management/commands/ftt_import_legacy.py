"""Import an original FTT database: ``manage.py ftt_import_legacy "host=... dbname=ftt ..."``
or ``manage.py ftt_import_legacy ftt_dump.sql``, ``--by ADMIN`` naming who imported."""

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from exchange.importer import ImportRefused, import_bundle
from exchange.legacy import LegacyBundle, LegacyError, open_source
from exchange.management.importing import add_by_argument, administrator


class Command(BaseCommand):
    help = _(
        "Import test events, their data and configuration from a database of the original "
        "FTT (PostgreSQL connection string) or from its plain SQL dump. Running it again "
        "adds nothing."
    )

    def add_arguments(self, parser):
        parser.add_argument(
            "source",
            help=_(
                "Path of a plain pg_dump file (e.g. ftt_dump.sql), or a libpq connection "
                "string / URL of the original database."
            ),
        )
        parser.add_argument(
            "--dry-run", action="store_true", help=_("Only print what would be imported.")
        )
        add_by_argument(parser)

    def handle(self, *args, source, dry_run, by=None, **options):
        user = administrator(by)
        try:
            original = open_source(source)
            try:
                bundle = LegacyBundle(original)
            finally:
                original.close()
            plan = import_bundle(bundle, dry_run=dry_run, by=user)
        except (LegacyError, ImportRefused) as exc:
            raise CommandError(str(exc)) from None
        for line in [*plan.lines(), plan.verdict()]:
            self.stdout.write(line)
