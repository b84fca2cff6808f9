"""The lean route for ``POST /api/poses/``: one pose from a robot, many a second.

Through Django's middleware, DRF and the ASGI adapter a single pose cost
5-11 ms of CPU, the storing statement a fraction of it.  This route answers
what it can alone with the same rule code the API view calls: the token and
its roles (common.api.authentication.token_account), the view's own
permission and throttle classes, the pose's one definition of fields and
ranges and the one storing statement (telemetry.api.single_pose).  Everything
else goes on, body and all, to Django: another method, address, body type or
renderer, a browser's Origin (CORS), a host not allowed, no token or a bad
one, a field it does not accept, an unknown or foreign segment, any error.
Django then answers exactly as before (4xx with field messages, 503 with
Retry-After).  Its answers carry the headers Django's middleware gives this
address (security headers, CSP, Vary), taken once per process from that
middleware.  It sits inside ftt_site.request_limits, so the body limits and
the request slots hold.
"""

import functools
import io
import json
import logging

from asgiref.sync import sync_to_async
from django.conf import settings
from django.core.exceptions import DisallowedHost
from django.core.handlers.asgi import ASGIRequest
from django.db import close_old_connections
from django.http import HttpResponse
from django.urls import resolve
from django.utils.cache import patch_vary_headers
from django.utils.module_loading import import_string
from rest_framework.exceptions import AuthenticationFailed
from rest_framework.renderers import JSONRenderer
from rest_framework.request import Request

from common.api.authentication import sent_key, token_account
from common.text import holds_lone_surrogate, may_hold_surrogate
from telemetry.api import single_pose
from telemetry.api.views import PoseViewSet

logger = logging.getLogger(__name__)

PATH = "/api/poses/"
# A single pose is a few hundred bytes; a bigger body is left to Django.
MAX_BODY = 16 * 1024
_JSON_TYPES = {b"application/json", b"application/json; charset=utf-8"}
_ACCEPTED = {None, b"*/*", b"application/json"}


def _refuse_constant(name):
    # DRF's parser refuses NaN and Infinity (strict JSON).
    raise ValueError(f"{name} is not JSON")


class PoseRoute:
    def __init__(self, app):
        self.app = app
        self._headers: dict[bool, list[tuple[bytes, bytes]]] = {}
        self._renderer = JSONRenderer()

    async def __call__(self, scope, receive, send):
        if not (
            scope["type"] == "http"
            and scope["method"] == "POST"
            and scope["path"] == PATH
            and not scope.get("query_string")
        ):
            return await self.app(scope, receive, send)
        headers = {}
        for name, value in scope["headers"]:
            # A repeated header is left to Django's rules for it.
            if name in headers:
                return await self.app(scope, receive, send)
            headers[name] = value
        key = sent_key(headers.get(b"authorization", b""))
        if (
            key is None
            or headers.get(b"content-type", b"").lower() not in _JSON_TYPES
            or headers.get(b"accept") not in _ACCEPTED
            or b"origin" in headers
        ):
            return await self.app(scope, receive, send)
        body, messages = await _read_body(receive)
        replay = _replaying(messages, receive)
        if body is None:
            return await self.app(scope, replay, send)
        answer = await sync_to_async(self.answer, thread_sensitive=False)(scope, key, body)
        if answer is None:
            return await self.app(scope, replay, send)
        status, content, headers = answer
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": content})

    def answer(self, scope, key, body):
        """(status, body, headers) when this route answers alone, else None.  Runs
        in a worker thread; its database connection goes back to the pool (or
        is closed) at the end, as at the end of a Django request."""
        try:
            return self._store(scope, key, body)
        except Exception:
            # Django answers it, with the message and status its handlers give.
            logger.debug("single pose left to Django", exc_info=True)
            return None
        finally:
            try:
                close_old_connections()
            except Exception:
                logger.warning("closing a database connection failed", exc_info=True)

    def _store(self, scope, key, body):
        try:
            data = json.loads(body, parse_constant=_refuse_constant)
        except ValueError:
            return None
        if may_hold_surrogate(body) and holds_lone_surrogate(data):
            # Django's JSON parser answers it (400).
            return None
        request = ASGIRequest(scope, io.BytesIO(body))
        try:
            request.get_host()
        except DisallowedHost:
            return None
        secure = request.is_secure()
        if settings.SECURE_SSL_REDIRECT and not secure:
            return None
        try:
            user, token = token_account(key)
        except AuthenticationFailed:
            return None
        api_request = Request(request)
        api_request.user, api_request.auth = user, token
        view = _view(api_request)
        if view is None:
            return None
        if not all(p.has_permission(api_request, view) for p in view.get_permissions()):
            return None
        # Counted as DRF counts: a request over the rate is left to Django,
        # which answers 429 with Retry-After.
        if not all(t.allow_request(api_request, view) for t in view.get_throttles()):
            return None
        # Before the pose is stored: after it, nothing may send the request on to
        # Django, which would store a pose sent without a uid a second time.
        headers = self._answer_headers(request, secure, view)
        answer = single_pose.store_sent(user, data)
        if answer is None:
            return None
        data, status = answer
        content = self._renderer.render(data)
        return status, content, [*headers, (b"content-length", str(len(content)).encode())]

    def _answer_headers(self, request, secure: bool, view) -> list[tuple[bytes, bytes]]:
        """The headers of the view's JSON answer after Django's middleware, run
        once (per scheme) through that middleware as configured."""
        known = self._headers.get(secure)
        if known is None:
            known = self._headers[secure] = _middleware_headers(request, view)
        return known


@functools.cache
def _resolved():
    # The URLconf does not change while the process runs.
    return resolve(PATH)


def _view(api_request):
    """The view Django would call for this request, made as DRF's ``as_view``
    makes it; None if the address is not (or no longer) the pose view's."""
    match = _resolved()
    actions = getattr(match.func, "actions", None)
    if getattr(match.func, "cls", None) is not PoseViewSet or actions.get("post") != "create":
        return None
    view = PoseViewSet(**match.func.initkwargs)
    actions = dict(actions)
    if "get" in actions:
        actions.setdefault("head", actions["get"])
    view.action_map = actions
    for method, action in actions.items():
        setattr(view, method, getattr(view, action))
    view.request, view.args, view.kwargs = api_request, match.args, match.kwargs
    view.format_kwarg, view.action = None, "create"
    return view


def _middleware_headers(request, view) -> list[tuple[bytes, bytes]]:
    response = HttpResponse(content_type="application/json")
    response["Allow"] = ", ".join(view.allowed_methods)
    patch_vary_headers(response, ["Accept"])

    def handler(_request):
        return response

    # Django builds its chain the same way (BaseHandler.load_middleware), the
    # first entry outermost.  No view runs, so no CSRF check; the request was
    # checked above (host, scheme) and carries no cookie or Origin.
    for path in reversed(settings.MIDDLEWARE):
        handler = import_string(path)(handler)
    answered = handler(request)
    if answered is not response:
        raise RuntimeError(f"the middleware answered {answered.status_code} by itself")
    if response.cookies:
        # Something of this request's own (a session, a CSRF cookie) that the
        # answers to every other request must not carry.
        raise RuntimeError("the middleware set a cookie")
    return [
        (name.lower().encode("latin-1"), value.encode("latin-1"))
        for name, value in response.items()
        if name.lower() != "content-length"
    ]


async def _read_body(receive):
    """(body, messages): the body when it is complete and small, else None; and
    the messages read, for Django to read again."""
    messages, chunks, size = [], [], 0
    while True:
        message = await receive()
        messages.append(message)
        if message["type"] != "http.request":
            return None, messages
        chunk = message.get("body", b"")
        chunks.append(chunk)
        size += len(chunk)
        if size > MAX_BODY:
            return None, messages
        if not message.get("more_body", False):
            return b"".join(chunks), messages


def _replaying(messages, receive):
    """A receive that gives the messages already read, then reads on."""
    pending = list(messages)

    async def replay():
        if pending:
            return pending.pop(0)
        return await receive()

    return replay
