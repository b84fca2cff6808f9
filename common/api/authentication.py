"""API tokens, checked with the account's groups in the same query, and cached
for a few seconds per process."""

import copy

from django.conf import settings
from django.db.models import F
from django.utils.translation import gettext_lazy as _
from rest_framework import authentication, exceptions
from rest_framework.authtoken.models import Token

from common import roles
from common.apps import DIRECTORY_BACKEND
from common.memo import Expiring

# key -> (user, token, group names, when the directory last checked the
# account's role or NOT_THE_DIRECTORYS).  A robot posting single poses sends the
# same token many times a second, so its lookup is cached rather than asked again.
# A token deleted, an account deactivated or a role changed through this
# process is forgotten at once (common.apps connects clear to those changes);
# through another process it is honoured within this many seconds.
known_tokens = Expiring(settings.FTT_TOKEN_CACHE_SECONDS)

KEYWORD = "Token"


def sent_key(header: bytes) -> str | None:
    """The key of an ``Authorization: Token <key>`` header as DRF's class reads it;
    None for anything else (no token, another scheme, a malformed header), which
    the class answers itself."""
    parts = header.split()
    if len(parts) != 2 or parts[0].lower() != KEYWORD.lower().encode():
        return None
    try:
        return parts[1].decode()
    except UnicodeError:
        return None


def token_account(key: str):
    """(user, token) for an API token: the account with its roles read along, a
    fresh copy per request.  Raises AuthenticationFailed for an unknown token or
    an inactive account.  DRF's class below and the single-pose route
    (ftt_site.inbound.pose_route) both ask this."""
    known = known_tokens.get(key)
    if known is None:
        known = _look_up(key)
        known_tokens.put(key, known)
    user, token, groups, directory_checked = known
    if directory_checked is not NOT_THE_DIRECTORYS:
        user, token, groups = _recheck_directory_role(key, known)
    # Each request gets its own copy: views and selectors keep per-request
    # things on the user object (common.roles, events.selectors.robots).
    user = copy.copy(user)
    roles.remember_groups(user, groups)
    return user, token


# The last field of a cached token for an account the directory did not make.
NOT_THE_DIRECTORYS = "local"


def _recheck_directory_role(key, known):
    """A directory account's token: its role is asked of the directory again
    when due (common.directory.recheck_role), never waiting for a place, so a
    slow directory holds this request for at most FTT_LDAP_TIMEOUT."""
    user, token, groups, checked = known
    if DIRECTORY_BACKEND not in settings.AUTHENTICATION_BACKENDS:
        return user, token, groups
    from common.directory import recheck_role, role_check_due

    if not role_check_due(checked):
        return user, token, groups
    outcome = recheck_role(user, wait=0)
    if outcome is None:
        return user, token, groups
    known_tokens.forget(key)
    if outcome is False:
        raise exceptions.AuthenticationFailed(_("Invalid token."))
    # The role may have changed: read it again.
    known = _look_up(key)
    known_tokens.put(key, known)
    return known[:3]


def _look_up(key):
    # One row per group (a single row with no group name for none).
    rows = list(
        Token.objects.select_related("user")
        .filter(key=key)
        .annotate(
            group_name=F("user__groups__name"),
            directory_account=F("user__directory_account__id"),
            directory_checked=F("user__directory_account__role_checked"),
        )
    )
    if not rows:
        raise exceptions.AuthenticationFailed(_("Invalid token."))
    user = rows[0].user
    if not user.is_active:
        raise exceptions.AuthenticationFailed(_("User inactive or deleted."))
    groups = frozenset(row.group_name for row in rows if row.group_name)
    first = rows[0]
    checked = first.directory_checked if first.directory_account else NOT_THE_DIRECTORYS
    return user, first, groups, checked


class TokenAuthentication(authentication.TokenAuthentication):
    """DRF's token check, reading the account's groups (its roles) with the token
    and the user: one query instead of two, and none while the token is cached."""

    keyword = KEYWORD

    def authenticate_credentials(self, key):
        return token_account(key)
