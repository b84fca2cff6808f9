"""Robot accounts: a login in the robot group, bound to vehicles, with a token."""

from dataclasses import dataclass

from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group
from django.core.exceptions import ValidationError
from django.db import transaction
from django.utils.translation import gettext
from rest_framework.authtoken.models import Token

from common import roles
from common.models import DirectoryAccount
from events.models import RobotAccount, Vehicle


@dataclass
class RobotLogin:
    account: RobotAccount
    token: str
    created: bool


@transaction.atomic
def ensure_robot_account(
    username: str, vehicles: list[Vehicle], *, new_token: bool = False
) -> RobotLogin:
    """Create the robot account ``username`` (or find it) and bind it to ``vehicles``
    as well as those it has; a token is made when it has none or ``new_token`` asks.

    A person's account is refused: it would lose its role and keep its password.
    """
    user, created = get_user_model().objects.get_or_create(username=username)
    if created:
        # Robots sign in with their token only.
        user.set_unusable_password()
        user.save(update_fields=["password"])
    elif not roles.is_robot(user) and (
        roles.user_role_rank(user) >= 0
        or user.is_staff
        or user.has_usable_password()
        # A directory person's, even with no role left (docs/accounts.md).
        or DirectoryAccount.objects.filter(user=user).exists()
    ):
        raise ValidationError(
            {
                "username": [
                    gettext("'%(name)s' is a person's account; give the robot its own name.")
                    % {"name": username}
                ]
            }
        )
    user.groups.add(Group.objects.get(name=roles.ROBOT))
    account, _ = RobotAccount.objects.get_or_create(user=user)
    account.vehicles.add(*vehicles)
    if new_token:
        Token.objects.filter(user=user).delete()
    token, _ = Token.objects.get_or_create(user=user)
    return RobotLogin(account=account, token=token.key, created=created)
