"""Back up the whole installation: ``manage.py ftt_backup ftt-backup.zip``.

Without ``--with-credentials`` the backup holds no session, API token or
password hash (exchange.backup), like the one administrators download; with it,
it is the machine owner's full copy, to be kept like the database itself."""

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from exchange.backup import BackupError, make_backup


class Command(BaseCommand):
    help = _(
        "Write the whole database (pg_dump on PostGIS, a consistent copy on SpatiaLite) and "
        "all media files into one zip. docs/data-exchange.md describes the restore."
    )

    def add_arguments(self, parser):
        parser.add_argument("output", help=_("Zip file to write."))
        parser.add_argument(
            "--with-credentials",
            action="store_true",
            help=_(
                "Keep sessions, API tokens and password hashes (a full copy for the "
                "machine's owner: whoever holds it can sign in as anyone)."
            ),
        )

    def handle(self, *args, output, with_credentials, **options):
        try:
            manifest = make_backup(output, credentials=with_credentials)
        except BackupError as exc:
            raise CommandError(str(exc)) from None
        database = next(n for n in manifest["members"] if n.startswith("database/"))
        self.stdout.write(
            _("Wrote %(output)s: %(database)s and %(files)s media file(s).")
            % {"output": output, "database": database, "files": manifest["counts"]["media_files"]}
        )
