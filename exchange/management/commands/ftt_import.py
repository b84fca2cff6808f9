"""Read an FTT archive into this installation:
``manage.py ftt_import ARCHIVE [--dry-run] [--by USER]``."""

from django.contrib.auth import get_user_model
from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from common import roles
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
        parser.add_argument(
            "--by",
            metavar="USER",
            help=_(
                "The administrator account the import's own changes are recorded as "
                "made by. Without it they name no one, and a final event refuses them."
            ),
        )

    def handle(self, *args, archive, dry_run, by=None, **options):
        user = _administrator(by) if by else None
        try:
            with open_archive(archive) as bundle:
                plan = import_bundle(bundle, dry_run=dry_run, by=user)
        except (ArchiveError, ImportRefused) as exc:
            raise CommandError(str(exc)) from None
        for line in [*plan.lines(), plan.verdict()]:
            self.stdout.write(line)


def _administrator(username: str):
    user = get_user_model().objects.filter(username=username, is_active=True).first()
    if user is None or not roles.has_role(user, roles.ADMINISTRATOR):
        raise CommandError(
            _("--by: %(user)s is no active administrator account here.") % {"user": username}
        )
    return user
