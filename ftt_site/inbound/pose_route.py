"""``POST /api/poses/`` without Django's request handling around it.

A robot sends single poses many times a second; Django's middleware, DRF's
view dispatch and the ASGI adapter's one thread per process cost more than
storing the pose.  This route answers such a request alone with the code the
API view runs: the token and its roles (common.api.authentication), the pose
view's permission and throttle classes, the quick check of a sent pose
(telemetry.api.serializers.sent_pose) and the one way a pose is stored and
answered (telemetry.api.single_pose).  Its answers carry the headers Django
gave this address's answer (security headers, CSP, Vary): the first request
of each scheme goes to Django, and the route keeps those headers.

Everything it does not take goes on, body and all, to Django, which answers
with its field messages: another method, address, body type or renderer, a
browser's Origin (CORS), a disallowed host, no token or a bad one, a body the
quick check refuses, a request over the rate.  That decision is made before
the request is counted against the rate and before anything is stored; from
then on the route answers itself, errors included (the API's exception
handler: 4xx with field messages, 503 with Retry-After), so no request is
counted or stored twice.  It sits inside ftt_site.inbound.limits, so the body
limits and the request slots hold.  A request it answers is counted in the
request and latency metrics by django-prometheus' own middleware, as Django
would have counted it (``_Counted``).
"""

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
from django_prometheus.middleware import PrometheusAfterMiddleware, PrometheusBeforeMiddleware
from django_prometheus.utils import Time
from rest_framework.exceptions import AuthenticationFailed
from rest_framework.renderers import JSONRenderer
from rest_framework.request import Request
from rest_framework.settings import api_settings

from common.api.authentication import sent_key, token_account
from common.text import holds_lone_surrogate, may_hold_surrogate
from ftt_site.inbound.proxies import settle
from telemetry.api import serializers, single_pose
from telemetry.api.views import PoseViewSet

logger = logging.getLogger(__name__)

PATH = "/api/poses/"
# A single pose is a few hundred bytes; a bigger body is left to Django.
MAX_BODY = 16 * 1024
_JSON_TYPES = {b"application/json", b"application/json; charset=utf-8"}
_ACCEPTED = {None, b"*/*", b"application/json"}
# Headers of Django's answer that belong to that answer alone.
_OWN_HEADERS = {b"content-length", b"date", b"server", b"set-cookie"}
INTERNAL_ERROR = {"detail": "Internal error; it has been logged.", "errors": {}}


def _refuse_constant(name):
    # DRF's parser refuses NaN and Infinity (strict JSON).
    raise ValueError(f"{name} is not JSON")


class _Learn:
    """Hand the request to Django and keep its answer's headers for ``secure``."""

    def __init__(self, secure: bool):
        self.secure = secure


class _Counted:
    """django-prometheus' two middlewares around a request this route answers:
    its counts by method, view and status, and its latency from the moment the
    route began with it (the body read)."""

    def __init__(self):
        def unused(request):
            raise AssertionError("the route answers the request itself")

        self.before = PrometheusBeforeMiddleware(unused)
        self.after = PrometheusAfterMiddleware(unused)

    def begin(self, request, started) -> None:
        request.resolver_match = resolve(PATH)
        self.before.process_request(request)
        self.after.process_request(request)
        # The latency counts from where the route began, as Django's would.
        request.prometheus_before_middleware_event = started
        request.prometheus_after_middleware_event = started
        self.after.process_view(request, None)

    def end(self, request, status: int, content: bytes) -> None:
        response = HttpResponse(content, status=status, content_type="application/json")
        self.after.process_response(request, response)
        self.before.process_response(request, response)


class PoseRoute:
    def __init__(self, app):
        self.app = app
        # Per scheme (https or not): Django's answer headers for this address.
        self._headers: dict[bool, list[tuple[bytes, bytes]]] = {}
        self._renderer = JSONRenderer()
        self._counted = _Counted()

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
        if isinstance(answer, _Learn):
            return await self.app(scope, replay, self._learning(send, answer.secure))
        status, content, headers = answer
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": content})

    def answer(self, scope, key, body):
        """(status, body, headers) when this route answers, None or a _Learn when
        Django does.  Runs in a worker thread; its database connection goes back
        to the pool (or is closed) at the end, as at the end of a Django request."""
        started = Time()
        try:
            checked = self._checked(scope, key, body)
            if checked is None or isinstance(checked, _Learn):
                return checked
            api_request, view, sent, secure = checked
            # Counted as DRF counts; a request over the rate is left to Django,
            # which answers 429 with Retry-After (a refused request is not counted).
            if not all(t.allow_request(api_request, view) for t in view.get_throttles()):
                return None
        except Exception:
            logger.debug("single pose left to Django", exc_info=True)
            close_old_connections()
            return None
        # From here on the request is counted and may be stored: it is answered here.
        request = api_request._request
        self._counted.begin(request, started)
        status = 500
        content = b""
        try:
            status, data, extra = self._stored(api_request, view, sent)
            content = self._renderer.render(data)
            headers = [*self._headers[secure], *extra]
            return status, content, [*headers, (b"content-length", str(len(content)).encode())]
        finally:
            self._counted.end(request, status, content)
            close_old_connections()

    def _checked(self, scope, key, body):
        """What storing needs, when everything before it says this route may answer."""
        try:
            data = json.loads(body, parse_constant=_refuse_constant)
        except ValueError:
            return None
        if may_hold_surrogate(body) and holds_lone_surrogate(data):
            # Django's JSON parser answers it (400).
            return None
        sent = serializers.sent_pose(data)
        if sent is None:
            return None
        request = ASGIRequest(scope, io.BytesIO(body))
        settle(request.META)
        try:
            request.get_host()
        except DisallowedHost:
            return None
        secure = request.is_secure()
        if settings.SECURE_SSL_REDIRECT and not secure:
            return None
        if secure not in self._headers:
            return _Learn(secure)
        try:
            user, token = token_account(key)
        except AuthenticationFailed:
            return None
        api_request = Request(request)
        api_request.user, api_request.auth = user, token
        view = PoseViewSet(
            request=api_request, action="create", args=(), kwargs={}, format_kwarg=None
        )
        if not all(p.has_permission(api_request, view) for p in view.get_permissions()):
            return None
        return api_request, view, sent, secure

    def _stored(self, api_request, view, sent) -> tuple[int, object, list]:
        """(status, body, extra headers): the pose stored, or the API's error answer."""
        try:
            data, status = single_pose.store(api_request.user, sent)
            return status, data, []
        except Exception as exc:
            context = {"view": view, "request": api_request, "args": (), "kwargs": {}}
            response = api_settings.EXCEPTION_HANDLER(exc, context)
            if response is None:
                logger.exception("single pose failed")
                return 500, INTERNAL_ERROR, []
            extra = [
                (name.lower().encode("latin-1"), value.encode("latin-1"))
                for name, value in response.items()
                if name.lower() not in {"content-type", "allow", "vary"}
            ]
            return response.status_code, response.data, extra

    def _learning(self, send, secure: bool):
        """``send`` that keeps the headers of Django's stored-pose answer."""

        async def learn(message):
            if message["type"] == "http.response.start" and message["status"] in (200, 201):
                names = {name.lower() for name, _ in message["headers"]}
                if b"set-cookie" not in names:
                    self._headers[secure] = [
                        (name.lower(), value)
                        for name, value in message["headers"]
                        if name.lower() not in _OWN_HEADERS
                    ]
            await send(message)

        return learn


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
