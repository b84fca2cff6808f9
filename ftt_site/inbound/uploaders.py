"""Who may send a large body to an upload address, decided from the request's
headers alone (ftt_site.inbound.limits asks before the body is read).

The account is the one Django and DRF would find: an ``Authorization: Token``
header, else the session cookie. The check is the coarse one of each address
(staff for the admin, the writing role of the API and import views); the views
still check everything else once the body has arrived.
"""

from importlib import import_module

from django.conf import settings
from django.contrib.auth import get_user
from django.http import HttpRequest
from django.http.cookie import parse_cookie
from rest_framework.exceptions import AuthenticationFailed

from common import roles
from common.api.authentication import sent_key, token_account

NOT_SIGNED_IN = "Sign in before sending a file this large."
NOT_ALLOWED = "Your account may not send a file this large to this address."


def _staff(user) -> bool:
    return user.is_active and user.is_staff


def _operator_or_robot(user) -> bool:
    # Robots send the photos and maps of their own vehicles (common.roles.ROBOT_WRITES).
    return roles.has_role(user, roles.OPERATOR) or roles.is_robot(user)


def _administrator(user) -> bool:
    return roles.has_role(user, roles.ADMINISTRATOR)


# Address prefix -> who may send it more than FTT_MAX_REQUEST_BODY.
UPLOADERS = {
    "/api/images/": _operator_or_robot,
    "/api/maps/": _operator_or_robot,
    "/api/archives/import/": _administrator,
    "/import/": _administrator,
    "/admin/": _staff,
}


def is_upload_path(path: str) -> bool:
    return path.startswith(tuple(UPLOADERS))


def header(scope, wanted: bytes) -> bytes | None:
    for name, value in scope.get("headers", ()):
        if name == wanted:
            return value
    return None


def account(scope):
    """The signed-in account of an ASGI request's headers, or None."""
    authorization = header(scope, b"authorization")
    if authorization is not None:
        key = sent_key(authorization)
        if key is None:
            return None
        try:
            return token_account(key)[0]
        except AuthenticationFailed:
            return None
    cookie = header(scope, b"cookie")
    if cookie is None:
        return None
    session_key = parse_cookie(cookie.decode("latin-1")).get(settings.SESSION_COOKIE_NAME)
    if not session_key:
        return None
    request = HttpRequest()
    request.session = import_module(settings.SESSION_ENGINE).SessionStore(session_key)
    user = get_user(request)
    return user if user.is_authenticated else None


def refusal(scope) -> tuple[int, str] | None:
    """None when the request's account may upload to its address, else (status, detail)."""
    user = account(scope)
    if user is None:
        return 401, NOT_SIGNED_IN
    for prefix, allowed in UPLOADERS.items():
        if scope["path"].startswith(prefix):
            return None if allowed(user) else (403, NOT_ALLOWED)
    return 403, NOT_ALLOWED
