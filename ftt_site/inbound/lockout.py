"""Failed sign-ins: who is stopped, and what a client then sees.

An address (a browser behind FTT's proxy) is locked by django-axes for
``FTT_LOGIN_COOLOFF_MINUTES`` after ``FTT_LOGIN_FAILURE_LIMIT`` failures,
whatever accounts it tried. An account is never locked by failures from other
addresses, or a stranger could lock anyone out: after that many failures
across all addresses it is only slowed down, to one attempt per
``FTT_LOGIN_ACCOUNT_PACE_SECONDS`` (:class:`AccountPace`). Either way the
client is told when it may try again, as a page, or as the API's JSON error,
with Retry-After (``locked_out``, axes' lockout hook). A directory that cannot
be reached is said as such (``DirectoryUnavailableMiddleware``) and counts as
no failure.
"""

import math
from datetime import timedelta

from axes.helpers import get_cool_off
from axes.models import AccessAttempt
from axes.utils import reset
from django.conf import settings
from django.core.exceptions import PermissionDenied
from django.db.models import Max, Sum
from django.http import JsonResponse
from django.shortcuts import render
from django.utils import timezone
from django.utils.translation import gettext as _
from django.utils.translation import ngettext

from ftt_site.inbound.proxies import client_of


def account_wait(username: str) -> int:
    """Seconds before ``username`` may be tried again (0: now)."""
    since = timezone.now() - get_cool_off()
    failed = AccessAttempt.objects.filter(username=username, attempt_time__gte=since).aggregate(
        failures=Sum("failures_since_start"), last=Max("attempt_time")
    )
    if (failed["failures"] or 0) < settings.AXES_FAILURE_LIMIT:
        return 0
    pace = timedelta(seconds=settings.FTT_LOGIN_ACCOUNT_PACE_SECONDS)
    return max(0, math.ceil((failed["last"] + pace - timezone.now()).total_seconds()))


class AccountPace:
    """After axes' own check: an account with many recent failures from anywhere
    may be tried once per pace. A refused attempt is answered like a lockout
    (axes' middleware, ``locked_out``) and not counted as a failure.

    An authentication backend that never signs anyone in, so it has no
    ``get_user``: a session is never bound to it."""

    def authenticate(self, request, username=None, **credentials):
        if request is None or not username:
            return None
        wait = account_wait(username)
        if wait:
            request.ftt_account_wait = wait
            request.axes_locked_out = True
            raise PermissionDenied
        return None


def _duration_text(seconds: int) -> str:
    if seconds < 60:
        return ngettext("%(n)s second", "%(n)s seconds", seconds) % {"n": seconds}
    minutes = math.ceil(seconds / 60)
    return ngettext("%(n)s minute", "%(n)s minutes", minutes) % {"n": minutes}


def _paused(request, message: str, status: int, seconds: int):
    if request.path.startswith("/api/"):
        response = JsonResponse({"detail": message, "errors": {}}, status=status)
    else:
        response = render(
            request, "registration/locked_out.html", {"message": message}, status=status
        )
    response["Retry-After"] = str(seconds)
    return response


def locked_out(request, original_response=None, credentials=None):
    seconds = getattr(request, "ftt_account_wait", None) or int(
        get_cool_off(request).total_seconds()
    )
    message = _("Too many failed sign-ins. Try again in %(wait)s.") % {
        "wait": _duration_text(seconds)
    }
    return _paused(request, message, 429, seconds)


class DirectoryUnavailableMiddleware:
    """A sign-in the directory could not answer (common.directory), on any login
    path: said as such, with Retry-After; it was no failed sign-in."""

    def __init__(self, get_response):
        self.get_response = get_response

    def __call__(self, request):
        return self.get_response(request)

    def process_exception(self, request, exception):
        # Here, not at the top: every process loads this module (ftt_site.apps),
        # and the LDAP client only matters where a directory signs people in.
        from common.directory import DirectoryUnavailable

        if not isinstance(exception, DirectoryUnavailable):
            return None
        seconds = exception.retry_after
        message = _(
            "The directory cannot be reached, so directory accounts cannot sign in now; "
            "local accounts still can. Try again in %(wait)s."
        ) % {"wait": _duration_text(seconds)}
        return _paused(request, message, 503, seconds)


def client_address(request) -> str | None:
    """Whose failures count together: the client's address as ftt_site.inbound.proxies
    reads it (behind a configured proxy, the address the proxy saw)."""
    return client_of(request.META)


def forgive_own_failures(sender, request, user, **kwargs) -> None:
    """``user_logged_in``: the account's own failures from this address are
    forgiven; other accounts' failures from it still count."""
    if request is not None:
        reset(ip=client_address(request), username=user.get_username())
