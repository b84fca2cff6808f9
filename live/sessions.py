"""A logout ends the live websockets opened in its session at once.

Each socket joins a channel-layer group named after its session (a hash of the
key, never the key itself); Django's ``user_logged_out`` signal, sent by every
logout before the session is flushed, tells that group. With Redis this
reaches every web process; without it, the process of the logout, which is
the only one when there is no Redis. The consumers' periodic check stays for
what no signal announces (a role taken away, a session that expired).
"""

import hashlib
import logging

from asgiref.sync import async_to_sync
from channels.layers import get_channel_layer
from django.contrib.auth.signals import user_logged_out

logger = logging.getLogger(__name__)

ENDED = "session.ended"


def session_group(session_key: str) -> str:
    return "ftt-session." + hashlib.sha256(session_key.encode()).hexdigest()[:40]


def end_live_sockets(sender, request, user, **kwargs) -> None:
    key = getattr(getattr(request, "session", None), "session_key", None)
    layer = get_channel_layer()
    if not key or layer is None:
        return
    try:
        async_to_sync(layer.group_send)(session_group(key), {"type": ENDED})
    except Exception:
        # The logout itself must succeed; the sockets' own check ends them later.
        logger.warning("telling the live sockets of a logout failed", exc_info=True)


def connect() -> None:
    user_logged_out.connect(end_live_sockets, dispatch_uid="ftt-live-logout")
