"""What the import commands share: the administrator an import's own changes
name (``--by``), as the signed-in user does for an upload."""

from django.contrib.auth import get_user_model
from django.core.management.base import CommandError
from django.utils.translation import gettext as _

from common import roles


def add_by_argument(parser) -> None:
    parser.add_argument(
        "--by",
        metavar="USER",
        help=_(
            "The administrator account the import's own changes are recorded as "
            "made by. Without it they name no one, and a final event refuses them."
        ),
    )


def administrator(username: str | None):
    """The active administrator named by ``--by``, or None without one."""
    if not username:
        return None
    user = get_user_model().objects.filter(username=username, is_active=True).first()
    if user is None or not roles.has_role(user, roles.ADMINISTRATOR):
        raise CommandError(
            _("--by: %(user)s is no active administrator account here.") % {"user": username}
        )
    return user
