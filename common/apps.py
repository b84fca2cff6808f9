from django.apps import AppConfig
from django.conf import settings
from django.core.signals import request_finished
from django.db import connection
from django.db.models.signals import m2m_changed, post_delete, post_save
from django.utils.translation import gettext_lazy as _

DIRECTORY_BACKEND = "common.directory.DirectoryBackend"


class CommonConfig(AppConfig):
    name = "common"
    verbose_name = _("Shared plumbing")

    def ready(self):
        from django.contrib.auth import get_user_model
        from django.contrib.auth.models import Group
        from rest_framework.authtoken.models import Token

        from common.api.authentication import known_tokens
        from common.metrics import observe_pool

        # Whatever may revoke or change what a cached token grants.
        user = get_user_model()
        for sender in (Token, user, Group):
            post_save.connect(known_tokens.clear, sender=sender, weak=False)
            post_delete.connect(known_tokens.clear, sender=sender, weak=False)
        m2m_changed.connect(known_tokens.clear, sender=user.groups.through, weak=False)

        # The pool gauges follow each request's end (common.metrics).
        request_finished.connect(
            lambda **kwargs: observe_pool(getattr(connection, "pool", None)),
            weak=False,
            dispatch_uid="ftt-pool-gauges",
        )
        # Only the directory backend sends these; without it the LDAP client
        # library stays unloaded.
        if DIRECTORY_BACKEND in settings.AUTHENTICATION_BACKENDS:
            from django_auth_ldap.backend import ldap_error, populate_user

            from common.directory import (
                DirectoryBackend,
                RoleCheckBackend,
                apply_directory_role,
                directory_unreachable,
                role_check_failed,
            )

            populate_user.connect(apply_directory_role, dispatch_uid="ftt-directory-role")
            ldap_error.connect(
                directory_unreachable, sender=DirectoryBackend, dispatch_uid="ftt-directory-down"
            )
            ldap_error.connect(
                role_check_failed, sender=RoleCheckBackend, dispatch_uid="ftt-role-check-down"
            )
