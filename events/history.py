"""Who changes a tracked row, through what and why (events.models.changes).

The web middleware (``ftt_site.change_origin``) names the channel of each
request; the collector and the importers wrap their writes in
:func:`authored`.  Writes outside both (shell, migrations, management
commands) are recorded as ``system``.  A reason given with an amendment of a
finalised event reaches every history row that amendment writes.
"""

import contextlib
from contextvars import ContextVar
from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Origin:
    channel: str = "system"
    user: object = None
    reason: str = ""
    request: object = None


_origin: ContextVar[Origin] = ContextVar(
    "ftt_change_origin",
    default=Origin(),  # noqa: B039  (frozen, never mutated)
)


def current_origin() -> Origin:
    return _origin.get()


@contextlib.contextmanager
def authored(channel: str | None = None, *, user=None, reason: str | None = None, request=None):
    """Attribute the writes inside to ``channel``/``user``/``reason``; what is not
    given stays as the surrounding context has it."""
    now = _origin.get()
    changes = {"channel": channel, "user": user, "reason": reason, "request": request}
    token = _origin.set(replace(now, **{k: v for k, v in changes.items() if v is not None}))
    try:
        yield
    finally:
        _origin.reset(token)


def stamp_origin(sender, history_instance, **kwargs) -> None:
    """simple-history's pre_create_historical_record: add channel, user and reason."""
    origin = _origin.get()
    history_instance.history_channel = origin.channel
    user = origin.user or getattr(origin.request, "user", None)
    if history_instance.history_user_id is None and getattr(user, "is_authenticated", False):
        history_instance.history_user = user
    if not history_instance.history_change_reason and origin.reason:
        history_instance.history_change_reason = origin.reason
