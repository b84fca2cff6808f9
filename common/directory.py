"""Sign-in from the directory (LDAP, Active Directory), kept apart from local accounts.

A directory sign-in only ever signs in, and changes, an account that a
directory sign-in made (``common.models.DirectoryAccount``). A name that is a
local account (the superuser, a local person, a robot) is never asked of the
directory: local accounts are checked first (``ModelBackend``), and
:class:`DirectoryBackend` refuses the rest of them without a network round
trip. A directory account is never a superuser or a robot; one that was made
either later is refused too.

``settings.FTT_LDAP_ROLE_GROUPS`` maps roles to directory groups. At every
directory sign-in the account gets the highest role whose group holds the
person, and loses the other people's roles, so a change in the directory
takes effect at the next sign-in. A robot's role is never given this way.

A directory that does not answer within ``FTT_LDAP_TIMEOUT`` seconds is taken
as unreachable for as long again: sign-ins are then refused at once with
:class:`DirectoryUnavailable` (said as such, not as a wrong password, and not
counted as a failed sign-in), and at most ``FTT_LDAP_MAX_SIGN_INS`` sign-ins
per process wait for it, so they never hold the request slots robots need.
"""

import logging
import math
import threading
import time
from contextlib import contextmanager

import ldap
from django.conf import settings
from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group
from django.db import transaction
from django.db.models import Q
from django_auth_ldap.backend import LDAPBackend

from common import roles
from common.models import DirectoryAccount

logger = logging.getLogger(__name__)

# The directory did not answer: nothing was learnt about the password.
UNREACHABLE = (
    ldap.SERVER_DOWN,
    ldap.TIMEOUT,
    ldap.CONNECT_ERROR,
    ldap.BUSY,
    ldap.UNAVAILABLE,
    ldap.TIMELIMIT_EXCEEDED,
)
# How long a sign-in waits for one of the process's directory places.
PLACE_WAIT_SECONDS = 1.0


class DirectoryUnavailable(Exception):
    """The directory cannot be asked now; try again in ``retry_after`` seconds."""

    def __init__(self, retry_after: float):
        super().__init__(f"the directory cannot be reached; retry in {retry_after:.0f} s")
        self.retry_after = max(1, math.ceil(retry_after))


def directory_role(group_dns) -> str | None:
    """The highest role mapped to one of ``group_dns``, or None."""
    held = {dn.lower() for dn in group_dns}
    mapped = settings.FTT_LDAP_ROLE_GROUPS
    for role in reversed(roles.ORDER):
        if mapped.get(role, "").lower() in held:
            return role
    return None


def _not_directory_accounts():
    """Accounts the directory must leave alone: local ones, superusers, robots."""
    return Q(directory_account__isnull=True) | Q(is_superuser=True) | Q(groups__name=roles.ROBOT)


def is_local_name(username: str) -> bool:
    """Whether ``username`` names an account the directory may not sign in."""
    named = get_user_model().objects.filter(username__iexact=username.strip())
    return named.filter(_not_directory_accounts()).exists()


def apply_directory_role(sender, user, ldap_user, **kwargs) -> None:
    """django-auth-ldap's ``populate_user``: runs before the account is saved."""
    role = directory_role(ldap_user.group_dns)
    if user.pk is None:
        with transaction.atomic():
            user.save()
            DirectoryAccount.objects.create(user=user)
    people = Group.objects.filter(name__in=roles.ORDER)
    user.groups.remove(*people.exclude(name=role))
    if role is not None:
        user.groups.add(people.get(name=role))


class _Gate:
    """Per process: how many sign-ins wait for the directory, and until when it
    is taken as unreachable."""

    def __init__(self):
        self.lock = threading.Lock()
        self.places = None
        self.down_until = 0.0

    def _places(self) -> threading.BoundedSemaphore:
        with self.lock:
            if self.places is None:
                self.places = threading.BoundedSemaphore(settings.FTT_LDAP_MAX_SIGN_INS)
            return self.places

    def pause_left(self) -> float:
        return max(0.0, self.down_until - time.monotonic())

    def went_down(self) -> float:
        pause = settings.FTT_LDAP_TIMEOUT
        with self.lock:
            self.down_until = max(self.down_until, time.monotonic() + pause)
        return pause

    @contextmanager
    def place(self):
        left = self.pause_left()
        if left:
            raise DirectoryUnavailable(left)
        places = self._places()
        if not places.acquire(timeout=PLACE_WAIT_SECONDS):
            raise DirectoryUnavailable(PLACE_WAIT_SECONDS)
        try:
            yield
        finally:
            places.release()


gate = _Gate()


def directory_unreachable(sender, context, user, request, exception, **kwargs) -> None:
    """django-auth-ldap's ``ldap_error``: an error raised here leaves the backend,
    so a directory that did not answer is not taken for a wrong password."""
    if isinstance(exception, UNREACHABLE):
        logger.warning("the directory did not answer (%s): %s", context, exception)
        raise DirectoryUnavailable(gate.went_down())


class DirectoryBackend(LDAPBackend):
    """django-auth-ldap's backend, for names that are no local account."""

    def authenticate(self, request, username=None, password=None, **kwargs):
        username = kwargs.get(get_user_model().USERNAME_FIELD, username)
        if not username or is_local_name(username):
            return None
        with gate.place():
            return super().authenticate(request, username=username, password=password)

    def get_or_build_user(self, username, ldap_user):
        user, built = super().get_or_build_user(username, ldap_user)
        if not built and (
            get_user_model().objects.filter(pk=user.pk).filter(_not_directory_accounts()).exists()
        ):
            # Made locally since the check in authenticate().
            logger.warning("directory sign-in as %s refused: a local account's name", username)
            raise ldap_user.AuthenticationFailed("a local account has this name")
        return user, built
