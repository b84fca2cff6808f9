"""What a client sees after too many failed logins (django-axes' lockout hook):
when it may try again, as a page, or as the API's JSON error, with Retry-After."""

import math

from axes.helpers import get_cool_off
from django.conf import settings
from django.http import JsonResponse
from django.shortcuts import render


def locked_out(request, original_response=None, credentials=None):
    seconds = int(get_cool_off(request).total_seconds())
    minutes = math.ceil(seconds / 60)
    message = (
        f"Too many failed sign-ins. Try again in {minutes} minute{'s' if minutes != 1 else ''}."
    )
    if request.path.startswith("/api/"):
        response = JsonResponse({"detail": message, "errors": {}}, status=429)
    else:
        response = render(request, "registration/locked_out.html", {"message": message}, status=429)
    response["Retry-After"] = str(seconds)
    return response


def client_address(request) -> str | None:
    """Whose failures count together: behind FTT's proxy every request comes from
    the proxy, which appends the address it saw to X-Forwarded-For."""
    forwarded = request.META.get("HTTP_X_FORWARDED_FOR", "")
    if settings.FTT_BEHIND_PROXY and forwarded:
        return forwarded.split(",")[-1].strip()
    return request.META.get("REMOTE_ADDR")
