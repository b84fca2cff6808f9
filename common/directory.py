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

Between sign-ins the directory is asked again (:func:`recheck_role`), at most
every ``FTT_LDAP_RECHECK_SECONDS`` per account: when the account's API token
or browser session is used, and on the worker's schedule
(``manage.py ftt_directory_recheck``). The same mapping as at sign-in applies
a changed role; an account whose role is gone (out of every role group, in the
deny group, or no longer in the directory) loses its roles, its API token and
its sessions. A directory that does not answer teaches nothing: everyone keeps
the last known role, and no request waits for a place.

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
from datetime import timedelta

import ldap
from django.conf import settings
from django.contrib.auth import get_user_model
from django.contrib.auth.models import Group
from django.core.exceptions import ObjectDoesNotExist
from django.db import transaction
from django.db.models import Q
from django.utils import timezone
from django_auth_ldap.backend import LDAPBackend, _LDAPUser
from rest_framework.authtoken.models import Token

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
            DirectoryAccount.objects.create(user=user, role_checked=timezone.now())
    else:
        DirectoryAccount.objects.filter(user=user).update(role_checked=timezone.now())
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
        # Whether the role checks' warning was logged since the directory last answered.
        self.silence_logged = False

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
    def place(self, wait: float = PLACE_WAIT_SECONDS):
        left = self.pause_left()
        if left:
            raise DirectoryUnavailable(left)
        places = self._places()
        if not places.acquire(timeout=wait):
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

    def get_user(self, user_id):
        """The account of a session signed in from the directory, its role
        asked again when due. An account whose role is gone comes back with a
        new session hash, so Django ends the session."""
        user = get_user_model().objects.select_related("directory_account").filter(pk=user_id)
        user = user.first()
        if user is None:
            return None
        try:
            due = role_check_due(user.directory_account.role_checked)
        except ObjectDoesNotExist:
            due = False
        # A changed role or staff flag is read again; an ended account keeps
        # the new session hash end_access() gave this object.
        if due and recheck_role(user, wait=0):
            user = get_user_model().objects.get(pk=user_id)
        _LDAPUser(self, user=user)  # django-auth-ldap's: sets user.ldap_user
        return user

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


# Role checks between sign-ins ------------------------------------------------


class _NothingLearnt(Exception):
    """The directory failed to answer a role check: nobody's role changes."""


class RoleCheckBackend(DirectoryBackend):
    """The same backend, its errors told apart from a sign-in's: django-auth-ldap
    takes a failed search for "no such person", which must not end anyone's
    access (``role_check_failed``)."""


def role_check_failed(sender, context, user, request, exception, **kwargs) -> None:
    """django-auth-ldap's ``ldap_error`` during a role check."""
    raise _NothingLearnt(exception)


def _checked_before():
    """Accounts last asked about before this are due again."""
    return timezone.now() - timedelta(seconds=settings.FTT_LDAP_RECHECK_SECONDS)


def _due(checked: str) -> Q:
    """``role_check_due`` as a filter on the field ``checked``."""
    return Q(**{f"{checked}__isnull": True}) | Q(**{f"{checked}__lt": _checked_before()})


def role_check_due(checked) -> bool:
    """Whether an account last asked about at ``checked`` should be asked again."""
    return checked is None or checked < _checked_before()


def _claim(user) -> bool:
    """Takes the account's next role check for this request (one per account
    and period, across all processes); False if it is not due or not the
    directory's."""
    directory_people = get_user_model().objects.exclude(_not_directory_accounts())
    claimed = DirectoryAccount.objects.filter(
        _due("role_checked"), user=user, user__in=directory_people
    )
    return bool(claimed.update(role_checked=timezone.now()))


def recheck_role(user, wait: float = PLACE_WAIT_SECONDS) -> bool | None:
    """Asks the directory for ``user``'s role again, as a sign-in would without
    the password, when it is due; waits at most ``wait`` seconds for a place.

    True: the account has a role from the directory (changed if it changed).
    False: its role is gone, and so are its roles, API token and sessions.
    None: nothing was learnt (not due, not the directory's, no place, the
    directory did not answer); the account keeps what it has.
    """
    try:
        with gate.place(wait):
            if not _claim(user):
                return None
            kept = _ask_role(user)
    except DirectoryUnavailable:
        return None
    if kept is False:
        end_access(user)
    return kept


def _ask_role(user) -> bool | None:
    backend = RoleCheckBackend()
    ldap_user = _LDAPUser(backend, username=backend.django_to_ldap_username(user.username))
    try:
        if ldap_user.dn is None:
            return False
        ldap_user._check_requirements()
        # Names, the staff flag and the role (apply_directory_role), as at sign-in.
        ldap_user._get_or_create_user(force_populate=True)
    except ldap_user.AuthenticationFailed:
        return False
    except (ldap.LDAPError, _NothingLearnt) as error:
        if not gate.silence_logged:
            gate.silence_logged = True
            logger.warning(
                "the directory did not answer a role check (%s); "
                "directory accounts keep their last known roles until it does",
                error,
            )
        gate.went_down()
        return None
    gate.silence_logged = False
    return True


def end_access(user) -> None:
    """A directory account without a directory role: no role, no staff flag,
    no API token, and a new session hash, which ends every session of it."""
    with transaction.atomic():
        account = get_user_model().objects.select_for_update().get(pk=user.pk)
        account.groups.remove(*Group.objects.filter(name__in=roles.ORDER))
        account.is_staff = False
        # Still no local password: only the session hash changes.
        account.set_unusable_password()
        account.save(update_fields=["is_staff", "password"])
        Token.objects.filter(user=account).delete()
    user.password = account.password
    logger.warning(
        "directory account %s has no role in the directory any more: "
        "its API token and sessions are ended",
        user,
    )


def recheck_due_accounts() -> dict[str, int]:
    """The worker's schedule: every directory account whose check is due.
    Counts of accounts kept, ended and not learnt about."""
    due = get_user_model().objects.exclude(_not_directory_accounts())
    due = due.filter(_due("directory_account__role_checked"))
    counts = {"kept": 0, "ended": 0, "unknown": 0}
    for user in due.order_by("pk"):
        outcome = recheck_role(user)
        counts[{True: "kept", False: "ended", None: "unknown"}[outcome]] += 1
    return counts
