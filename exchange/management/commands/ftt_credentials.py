"""``manage.py ftt_credentials save FILE`` before restoring a backup without
credentials, ``manage.py ftt_credentials restore FILE`` after it
(exchange.credentials)."""

from pathlib import Path

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from exchange.credentials import restore_credentials, save_credentials


class Command(BaseCommand):
    help = _(
        "Save every account's password hash, API token, role and flags to a file (0600), or "
        "give them back after a backup without credentials was restored."
    )

    def add_arguments(self, parser):
        parser.add_argument(
            "action", choices=["save", "restore"], help=_("Save before, restore after.")
        )
        parser.add_argument("file", type=Path, help=_("File that keeps the sign-ins."))

    def handle(self, *args, action, file, **options):
        if action == "save":
            count = save_credentials(file)
            self.stdout.write(
                _("Saved the sign-ins of %(count)s account(s) to %(file)s.")
                % {"count": count, "file": file}
            )
            return
        try:
            done = restore_credentials(file)
        except (OSError, ValueError, KeyError) as exc:
            raise CommandError(
                _("Cannot restore sign-ins from %(file)s: %(exc)s") % {"file": file, "exc": exc}
            ) from None
        self.stdout.write(
            _("Sign-ins restored: %(kept)s account(s) kept, %(made)s made again.")
            % {"kept": done["kept"], "made": done["made"]}
        )
