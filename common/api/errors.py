"""One JSON error shape for the whole API: ``{"detail": ..., "errors": {field: [..]}}``."""

import logging
import sys

from django.core.exceptions import ValidationError as DjangoValidationError
from django.db import DatabaseError, IntegrityError, InterfaceError, OperationalError
from django.db.models import ProtectedError, RestrictedError
from django.http import HttpResponse, JsonResponse
from django.views import defaults
from rest_framework import status
from rest_framework.response import Response
from rest_framework.views import exception_handler as drf_exception_handler

from common.errors import NotFound, RuleViolation, TooManyWaiting, describe_protected

logger = logging.getLogger(__name__)


def _field_errors(exc: DjangoValidationError) -> dict:
    if hasattr(exc, "error_dict"):
        return {field: [str(m) for m in msgs] for field, msgs in exc.message_dict.items()}
    return {"non_field_errors": [str(m) for m in exc.messages]}


def _first_message(errors) -> str:
    """The first message anywhere in DRF's nested errors (lists of items nest as dicts)."""
    if isinstance(errors, dict):
        errors = list(errors.values())
    if isinstance(errors, list):
        return next((m for m in map(_first_message, errors) if m), "")
    return str(errors)


# PostgreSQL's serialization failure and deadlock: the transaction was rolled back whole.
_TRANSIENT_PGCODES = {"40001", "40P01"}


def _is_transient_conflict(exc) -> bool:
    cause = exc.__cause__
    # psycopg 3 names the code ``sqlstate``, psycopg2 ``pgcode``.
    code = getattr(cause, "sqlstate", None) or getattr(cause, "pgcode", None)
    return isinstance(exc, DatabaseError) and code in _TRANSIENT_PGCODES


# Seconds a client is asked to wait when the server, not its request, was the problem.
RETRY_AFTER_SECONDS = 2
BUSY_DETAIL = "The server is busy or its database is unreachable; nothing was written. Retry."


def is_server_state(exc) -> bool:
    """Database busy or locked, unreachable, out of connections or pool slots.

    Django wraps all of these (SQLite "database is locked", PostgreSQL "too many
    clients", a psycopg pool timeout, a lost connection) as OperationalError or
    InterfaceError; a wrong value is a DataError and stays the client's fault.
    """
    return isinstance(exc, OperationalError | InterfaceError) and not _is_transient_conflict(exc)


def _busy_headers() -> dict:
    return {"Retry-After": str(RETRY_AFTER_SECONDS)}


def exception_handler(exc, context):
    if isinstance(exc, DjangoValidationError):
        errors = _field_errors(exc)
        code = status.HTTP_400_BAD_REQUEST
        if isinstance(exc, RuleViolation):
            code = status.HTTP_409_CONFLICT
        elif isinstance(exc, NotFound):
            code = status.HTTP_404_NOT_FOUND
        detail = "; ".join(m for msgs in errors.values() for m in msgs)
        if isinstance(exc, TooManyWaiting):
            retry = {"Retry-After": str(exc.retry_after)}
            return Response({"detail": detail, "errors": errors}, status=429, headers=retry)
        return Response({"detail": detail, "errors": errors}, status=code)
    if isinstance(exc, ProtectedError | RestrictedError):
        detail = describe_protected(exc)
        return Response({"detail": detail, "errors": {"non_field_errors": [detail]}}, status=409)
    if isinstance(exc, IntegrityError) or _is_transient_conflict(exc):
        # Only reached when two requests race past the service checks (or the
        # database chose one of two to abort); nothing was written, so report
        # a conflict to retry, not a crash and not a bad value.
        logger.info("concurrent conflict: %s", exc)
        detail = "This change conflicts with another one made at the same time; retry."
        return Response({"detail": detail, "errors": {"non_field_errors": [detail]}}, status=409)
    if is_server_state(exc):
        logger.warning("refused while the database is unavailable: %s", exc)
        body = {"detail": BUSY_DETAIL, "errors": {"non_field_errors": [BUSY_DETAIL]}}
        return Response(body, status=503, headers=_busy_headers())
    if isinstance(exc, DatabaseError | ValueError | OverflowError):
        logger.warning("rejected request: %s", exc)
        detail = "The request contains a value the database cannot store."
        return Response({"detail": detail, "errors": {"non_field_errors": [detail]}}, status=400)
    response = drf_exception_handler(exc, context)
    if response is not None and isinstance(response.data, dict) and "detail" in response.data:
        response.data = {"detail": str(response.data["detail"]), "errors": {}}
    elif response is not None:
        errors = (
            response.data
            if isinstance(response.data, dict)
            else {"non_field_errors": response.data}
        )
        response.data = {"detail": _first_message(errors) or "Invalid input.", "errors": errors}
    return response


def _outside_drf(request, status: int, detail: str, fallback, *args):
    """URLs under /api/ that no view matched (or a crash outside DRF) still answer JSON."""
    if request.path.startswith("/api/"):
        return JsonResponse({"detail": detail, "errors": {}}, status=status)
    return fallback(request, *args)


def not_found(request, exception):
    return _outside_drf(
        request,
        404,
        "There is no API endpoint at this address.",
        defaults.page_not_found,
        exception,
    )


def server_error(request):
    # Called inside Django's ``except`` block, so the exception is still at hand:
    # a database that is busy or down fails every page (login, GUI, sessions),
    # and that is the server's state, not an internal error.
    if is_server_state(sys.exc_info()[1]):
        response = JsonResponse({"detail": BUSY_DETAIL, "errors": {}}, status=503)
        if not request.path.startswith("/api/"):
            response = HttpResponse(BUSY_DETAIL, status=503, content_type="text/plain")
        response.headers.update(_busy_headers())
        return response
    return _outside_drf(request, 500, "Internal error; it has been logged.", defaults.server_error)
