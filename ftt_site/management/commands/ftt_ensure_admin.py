"""Make sure an administrator account exists (used by scripts/run.sh).

The account is named by FTT_ADMIN_USER (default "admin"); FTT_ADMIN_EMAIL and
FTT_ADMIN_PASSWORD are optional. Without a password in the environment a new
account gets a random one, printed once and kept in <data dir>/admin_password.txt
(mode 0600). Running the command again changes nothing unless FTT_ADMIN_PASSWORD
differs from the stored password; then the file is removed.
"""

import os
import secrets
from pathlib import Path

from django.conf import settings
from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group
from django.core.management.base import BaseCommand
from django.db import transaction
from django.utils.translation import gettext as _

from common.roles import ADMINISTRATOR

PASSWORD_FILE = "admin_password.txt"


def _write_private(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    path.chmod(0o600)  # O_CREAT's mode does not apply to an existing file


class Command(BaseCommand):
    help = _("Create or repair the administrator account named by FTT_ADMIN_USER.")

    def handle(self, *args, **options):
        username = os.environ.get("FTT_ADMIN_USER", "").strip() or "admin"
        email = os.environ.get("FTT_ADMIN_EMAIL", "").strip()
        password = os.environ.get("FTT_ADMIN_PASSWORD", "")
        password_file = Path(settings.DATA_DIR) / PASSWORD_FILE
        User = get_user_model()

        with transaction.atomic():
            user = User.objects.filter(username=username).first()
            created = user is None
            generated = False
            if created:
                user = User(username=username, email=email)
                if not password:
                    password = secrets.token_urlsafe(12)
                    generated = True
                user.set_password(password)
            elif password and not user.check_password(password):
                user.set_password(password)
                self.stdout.write(
                    _("Password of '%(user)s' set from FTT_ADMIN_PASSWORD.") % {"user": username}
                )
            if email and user.email != email:
                user.email = email
            user.is_active = user.is_staff = user.is_superuser = True
            user.save()
            group = Group.objects.filter(name=ADMINISTRATOR).first()
            if group is not None:
                user.groups.add(group)

        if generated:
            _write_private(password_file, password + "\n")
            self.stdout.write(
                _(
                    "Created administrator '%(user)s' with password: %(password)s\n"
                    "(also stored in %(file)s)"
                )
                % {"user": username, "password": password, "file": password_file}
            )
            return
        if password:
            # A password given in the environment replaces a generated one.
            password_file.unlink(missing_ok=True)
        line = (
            _("Created administrator '%(user)s'.")
            if created
            else _("Checked administrator '%(user)s'.")
        )
        self.stdout.write(line % {"user": username})
        if password_file.exists() and user.check_password(password_file.read_text().strip()):
            self.stdout.write(_("Its password is in %(file)s.") % {"file": password_file})
