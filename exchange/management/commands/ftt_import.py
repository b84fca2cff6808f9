"""Read an FTT archive into this installation: ``manage.py ftt_import ARCHIVE [--dry-run]``."""

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from exchange.archive import ArchiveError, open_archive
from exchange.importer import ImportRefused, import_bundle


class Command(BaseCommand):
    help = _(
        "Import an archive written by ftt_export. All or nothing; importing the same "
        "archive again changes nothing."
    )

    def add_arguments(self, parser):
        parser.add_argument("archive", help=_("Archive file written by ftt_export."))
        parser.add_argument(
            "--dry-run",
            action="store_true",
            help=_("Only print what would be added, updated and reused."),
        )

    def handle(self, *args, archive, dry_run, **options):
        try:
            with open_archive(archive) as bundle:
                plan = import_bundle(bundle, dry_run=dry_run)
        except (ArchiveError, ImportRefused) as exc:
            raise CommandError(str(exc)) from None
        for line in [*plan.lines(), plan.verdict()]:
            self.stdout.write(line)
