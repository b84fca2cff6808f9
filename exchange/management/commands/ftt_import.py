"""Read an FTT archive into this installation:
``manage.py ftt_import ARCHIVE [--dry-run] [--by USER]``."""

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from exchange.archive import ArchiveError, open_archive
from exchange.importer import ImportRefused, import_bundle
from exchange.management.importing import add_by_argument, administrator


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
        add_by_argument(parser)

    def handle(self, *args, archive, dry_run, by=None, **options):
        user = administrator(by)
        try:
            with open_archive(archive) as bundle:
                plan = import_bundle(bundle, dry_run=dry_run, by=user)
        except (ArchiveError, ImportRefused) as exc:
            raise CommandError(str(exc)) from None
        for line in [*plan.lines(), plan.verdict()]:
            self.stdout.write(line)
