"""Who changes a tracked row, through what and why (events.models.changes).

The web middleware (``ftt_site.inbound.change_origin``) names the channel of each
request; the collector and the importers wrap their writes in
:func:`authored`.  Writes outside both (shell, migrations, management
commands) are recorded as ``system``.  A reason given with an amendment of a
finalised event reaches every history row that amendment writes.
"""

import contextlib
import functools
from contextvars import ContextVar
from dataclasses import dataclass, replace

from django.db import connection
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


def _origin_channel(origin: Origin) -> str:
    # The REST API's route, signed in by the pages' session (DRF leaves no
    # ``auth`` then), is the GUI's; by a token, the API's.
    request = origin.request
    if origin.channel == "api" and request is not None and getattr(request, "auth", None) is None:
        return "gui"
    return origin.channel


def stamp_origin(sender, history_instance, **kwargs) -> None:
    """simple-history's pre_create_historical_record: add channel, user and reason.

    Every entry written through it is a change made here (``history_source``
    empty); entries another installation recorded are written by the archive
    import, without these signals."""
    origin = _origin.get()
    history_instance.history_channel = _origin_channel(origin)
    user = _origin_user()
    if history_instance.history_user_id is None and user is not None:
        history_instance.history_user = user
    if not history_instance.history_change_reason and origin.reason:
        history_instance.history_change_reason = origin.reason


# Reading a model's ``history`` builds a manager class each time.
_history_model = functools.cache(get_history_model_for_model)


def write_history(model, *, changed=(), created=()) -> None:
    """The history entries of rows written without them (simple-history's
    ``save_without_historical_record``, an ``update``), stamped as
    :func:`stamp_origin` stamps one, all in one INSERT.

    The values are copied from the stored rows, so an entry holds what the
    database holds even where an update computed it there (``Greatest``).
    simple-history's ``bulk_history_create`` writes one kind per call and
    builds an object per entry; a change of mode both closes and creates
    rows, and it is the collector's busiest write."""
    kinds = {row.pk: "~" for row in changed} | {row.pk: "+" for row in created}
    if not kinds:
        return
    origin = _origin.get()
    history = _history_model(model)
    user = _origin_user()
    quote = connection.ops.quote_name
    copied = ", ".join(quote(field.column) for field in history.tracked_fields)
    pk = quote(model._meta.pk.column)
    created_ids = [pk_ for pk_, kind in kinds.items() if kind == "+"]
    is_created = f"{pk} IN ({', '.join(['%s'] * len(created_ids))})" if created_ids else "1 = 0"
    sql = (
        f"INSERT INTO {quote(history._meta.db_table)} ({copied}, history_date, history_type,"
        " history_user_id, history_change_reason, history_channel, history_author,"
        " history_source)"
        f" SELECT {copied}, %s, CASE WHEN {is_created} THEN '+' ELSE '~' END, %s, %s, %s, '', ''"
        f" FROM {quote(model._meta.db_table)} WHERE {pk} IN ({', '.join(['%s'] * len(kinds))})"
    )
    params = [
        connection.ops.adapt_datetimefield_value(timezone.now()),
        *created_ids,
        user.pk if user is not None else None,
        origin.reason or None,
        _origin_channel(origin),
        *kinds,
    ]
    with connection.cursor() as cursor:
        cursor.execute(sql, params)
