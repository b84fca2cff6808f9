"""Back up the whole installation: ``manage.py ftt_backup ftt-backup.zip``."""

from django.core.management.base import BaseCommand, CommandError

from exchange.backup import BackupError, make_backup


class Command(BaseCommand):
    help = (
        "Write the whole database (pg_dump on PostGIS, a consistent copy on SpatiaLite) and "
        "all media files into one zip. docs/data-exchange.md describes the restore."
    )

    def add_arguments(self, parser):
        parser.add_argument("output", help="Zip file to write.")

    def handle(self, *args, output, **options):
        try:
            manifest = make_backup(output)
        except BackupError as exc:
            raise CommandError(str(exc)) from None
        database = next(n for n in manifest["members"] if n.startswith("database/"))
        self.stdout.write(
            f"Wrote {output}: {database} and {manifest['counts']['media_files']} media file(s)."
        )
