"""Whose address a request comes from: the one rule for forwarded headers.

Only a configured proxy (``FTT_BEHIND_PROXY=1``, the networks of
``FTT_PROXY_ADDRESSES``) may say where a request came from. From one of them,
the client is the first address of ``X-Forwarded-For`` from the right that is
no configured proxy (each proxy appends the address it saw; what a client sent
itself stands further left). ``REMOTE_ADDR`` becomes that address, so that
every reader (who may read /metrics, whose failed sign-ins count together, the
API's throttle) sees the same one. From anybody else the forwarded headers are
dropped before anything reads them, ``X-Forwarded-Proto`` too.

The production server's Uvicorn does not apply forwarded headers itself
(``ftt_site/server/web_worker.py``): this is their only reader.
"""

import ipaddress

from django.conf import settings

FORWARDED_HEADERS = (
    "HTTP_X_FORWARDED_FOR",
    "HTTP_X_FORWARDED_PROTO",
    "HTTP_X_FORWARDED_HOST",
    "HTTP_X_FORWARDED_PORT",
    "HTTP_X_REAL_IP",
    "HTTP_FORWARDED",
)


def _address(text: str):
    try:
        address = ipaddress.ip_address(text.strip())
    except ValueError:
        return None
    # A proxy on an IPv6 socket may be seen as ::ffff:10.1.1.1.
    return getattr(address, "ipv4_mapped", None) or address


def _is_proxy(address) -> bool:
    if address is None or not settings.FTT_BEHIND_PROXY:
        return False
    return any(address in network for network in settings.FTT_PROXY_NETWORKS)


def client_of(meta: dict) -> str | None:
    """The client's address for a request's ``META`` as the peer sent it."""
    peer = meta.get("REMOTE_ADDR")
    client = _address(peer or "")
    if not _is_proxy(client):
        return peer
    for entry in reversed(meta.get("HTTP_X_FORWARDED_FOR", "").split(",")):
        seen = _address(entry)
        if seen is None:
            break
        client = seen
        if not _is_proxy(seen):
            break
    return str(client)


def settle(meta: dict) -> None:
    """The client's address in ``REMOTE_ADDR``, and forwarded headers only where
    a configured proxy sent them, in a request's ``META``."""
    from_proxy = _is_proxy(_address(meta.get("REMOTE_ADDR") or ""))
    meta["REMOTE_ADDR"] = client_of(meta)
    # The chain is read; the scheme (SECURE_PROXY_SSL_HEADER) only from a proxy.
    meta.pop("HTTP_X_FORWARDED_FOR", None)
    if not from_proxy:
        for header in FORWARDED_HEADERS:
            meta.pop(header, None)


class ForwardedHeadersMiddleware:
    """First of all middleware: :func:`settle` before anything reads the request.
    The lean pose route (ftt_site.inbound.pose_route), which Django's middleware does
    not see, settles its requests itself."""

    def __init__(self, get_response):
        self.get_response = get_response

    def __call__(self, request):
        settle(request.META)
        return self.get_response(request)
