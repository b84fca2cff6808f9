"""API tokens, checked with the account's groups in the same query, and kept
for a few seconds per process."""

import copy

from django.conf import settings
from django.db.models import F
from django.utils.translation import gettext_lazy as _
from rest_framework import authentication, exceptions

from common import roles
from common.memo import Expiring

# key -> (user, token, group names).  A robot posting single poses sends the
# same token many times a second; each lookup was a round trip of its own.
# A token deleted, an account deactivated or a role changed through this
# process is forgotten at once (common.apps connects clear to those changes);
# through another process it is honoured within this many seconds.
known_tokens = Expiring(settings.FTT_TOKEN_CACHE_SECONDS)


class TokenAuthentication(authentication.TokenAuthentication):
    """DRF's token check, reading the account's groups (its roles) with the token
    and the user: one query instead of two, and none while the token is kept."""

    def authenticate_credentials(self, key):
        known = known_tokens.get(key)
        if known is None:
            known = self._look_up(key)
            known_tokens.put(key, known)
        user, token, groups = known
        # Each request gets its own copy: views and selectors keep per-request
        # things on the user object (common.roles, events.selectors.robots).
        user = copy.copy(user)
        roles.remember_groups(user, groups)
        return user, token

    def _look_up(self, key):
        # One row per group (a single row with no group name for none).
        rows = list(
            self.get_model()
            .objects.select_related("user")
            .filter(key=key)
            .annotate(group_name=F("user__groups__name"))
        )
        if not rows:
            raise exceptions.AuthenticationFailed(_("Invalid token."))
        user = rows[0].user
        if not user.is_active:
            raise exceptions.AuthenticationFailed(_("User inactive or deleted."))
        groups = frozenset(row.group_name for row in rows if row.group_name)
        return user, rows[0], groups
