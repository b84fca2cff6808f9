"""API tokens, checked with the account's groups in the same query."""

from django.db.models import F
from django.utils.translation import gettext_lazy as _
from rest_framework import authentication, exceptions

from common import roles


class TokenAuthentication(authentication.TokenAuthentication):
    """DRF's token check, reading the account's groups (its roles) with the token
    and the user: one query instead of two on every robot and script request,
    whose round trips to the database are most of a single pose's time."""

    def authenticate_credentials(self, key):
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
        roles.remember_groups(user, (row.group_name for row in rows if row.group_name))
        return user, rows[0]
