"""Which tile servers an external (URL) layer may name.

Browsers load its tiles, and so does the report worker on the server: an
address there is a request the server makes. So only ``http(s)`` to the hosts
an administrator allowed in ``FTT_TILE_HOSTS``: a name exactly, or ``*.domain``
for the names below it. An IP address, ``localhost`` and the like count only
when listed exactly, so loopback, link-local and private addresses need an
administrator to name them; a pattern never matches them.
"""

import ipaddress
from urllib.parse import urlsplit

from django.conf import settings
from django.core.exceptions import ValidationError
from django.utils.translation import gettext as _

LOCAL_NAMES = ("localhost", ".localhost", ".local", ".internal")


def _matches(host: str, entry: str) -> bool:
    if entry.startswith("*."):
        return host.endswith(entry[1:]) and not _is_address_or_local(host)
    return host == entry


def _is_address_or_local(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return host == LOCAL_NAMES[0] or host.endswith(LOCAL_NAMES[1:])
    return True


def check_tile_url(url: str) -> None:
    """Raise ValidationError unless ``url`` names an allowed tile server."""
    try:
        parts = urlsplit(url)
        host = (parts.hostname or "").lower()
    except ValueError:
        parts, host = None, ""
    if parts is None or parts.scheme not in ("http", "https") or not host:
        raise ValidationError(
            _("A tile server address starts with http:// or https:// and a host.")
        )
    if parts.username or parts.password:
        raise ValidationError(_("A tile server address carries no user name or password."))
    allowed = [entry.strip().lower() for entry in settings.FTT_TILE_HOSTS]
    if not any(_matches(host, entry) for entry in allowed):
        raise ValidationError(
            _(
                "%(host)s is not among the tile servers an administrator allowed "
                "(FTT_TILE_HOSTS: %(allowed)s)."
            )
            % {"host": host, "allowed": ", ".join(allowed) or "none"}
        )
