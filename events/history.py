"""Who changes a tracked row, through what and why (events.models.changes).

The web middleware (``ftt_site.change_origin``) names the channel of each
request; the collector and the importers wrap their writes in
:func:`authored`.  Writes outside both (shell, migrations, management
commands) are recorded as ``system``.  A reason given with an amendment of a
finalised event reaches every history row that amendment writes.
"""

import contextlib
import functools
from contextvars import ContextVar
from dataclasses import dataclass, replace

from django.utils import timezone
from simple_history.utils import get_history_model_for_model


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


def _origin_user():
    origin = _origin.get()
    user = origin.user or getattr(origin.request, "user", None)
    return user if getattr(user, "is_authenticated", False) else None


def stamp_origin(sender, history_instance, **kwargs) -> None:
    """simple-history's pre_create_historical_record: add channel, user and reason."""
    origin = _origin.get()
    history_instance.history_channel = origin.channel
    user = _origin_user()
    if history_instance.history_user_id is None and user is not None:
        history_instance.history_user = user
    if not history_instance.history_change_reason and origin.reason:
        history_instance.history_change_reason = origin.reason


# Reading a model's ``history`` builds a manager class each time.
_history_model = functools.cache(get_history_model_for_model)


def write_history(model, *, changed=(), created=()) -> None:
    """The history entries of rows written without them (simple-history's
    ``save_without_historical_record``, a ``bulk_update``), stamped as
    :func:`stamp_origin` stamps one, all in one INSERT.

    simple-history's ``bulk_history_create`` writes one kind per call; a change
    of mode both closes and creates rows, and its entries are one write here."""
    origin = _origin.get()
    history = _history_model(model)
    stamp = {
        "history_date": timezone.now(),
        "history_user": _origin_user(),
        "history_change_reason": origin.reason or None,
        "history_channel": origin.channel,
    }
    entries = [
        history(
            history_type=kind,
            **stamp,
            **{field.attname: getattr(row, field.attname) for field in history.tracked_fields},
        )
        for kind, rows in (("~", changed), ("+", created))
        for row in rows
    ]
    history.objects.bulk_create(entries)
