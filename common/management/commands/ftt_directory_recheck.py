"""``manage.py ftt_directory_recheck``: asks the directory for the role of
every directory account not asked about for ``FTT_LDAP_RECHECK_SECONDS``
(the worker runs it that often), and ends the API tokens and sessions of the
accounts whose role is gone (common.directory.recheck_role)."""

from django.conf import settings
from django.core.management.base import BaseCommand
from django.utils.translation import gettext as _

from common.apps import DIRECTORY_BACKEND


class Command(BaseCommand):
    help = _("Ask the directory again for the roles of the accounts it made.")

    def handle(self, *args, **options):
        if DIRECTORY_BACKEND not in settings.AUTHENTICATION_BACKENDS:
            self.stdout.write(_("no directory is configured (FTT_LDAP_SERVER_URI)"))
            return
        from common.directory import recheck_due_accounts

        counts = recheck_due_accounts()
        self.stdout.write(
            _("directory roles: %(kept)d kept, %(ended)d ended, %(unknown)d not answered") % counts
        )
