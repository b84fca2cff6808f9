"""Small helpers shared by the service modules."""

from datetime import datetime

from django.db.models import Max, Model
from django.utils import timezone
from django.utils.translation import gettext as _

from common.errors import RuleViolation


def instant(at: datetime | None) -> datetime:
    if at is None:
        return timezone.now()
    if timezone.is_naive(at):
        raise ValueError("Times must be timezone-aware.")
    return at


def lock(model_instance: Model, *read_along: str) -> Model:
    """Re-read a row with a row lock held until the surrounding transaction ends;
    ``read_along`` names related rows read in the same query, not locked.

    NO KEY UPDATE: writers that lock the same row still queue, but a row that
    only references it (a note's foreign key, checked at COMMIT with KEY SHARE)
    does not wait for it; FOR UPDATE would make such commits deadlock with
    concurrent mode reports."""
    rows = type(model_instance).objects.select_related(*read_along)
    return rows.select_for_update(no_key=True, of=("self",)).get(pk=model_instance.pk)


def next_number(queryset) -> int:
    # max+1, not count+1: numbers people wrote down stay valid after a delete.
    return (queryset.aggregate(n=Max("number"))["n"] or 0) + 1


def require_open(entry, label: str) -> None:
    if entry.end is not None:
        raise RuleViolation(
            _("%(entry)s is closed; re-open it or pick an open one.") % {"entry": label},
            code="closed",
        )


def require_not_before(entry, at: datetime, label: str) -> None:
    if at < entry.start:
        raise RuleViolation(
            _("%(entry)s started at %(start)s, after %(at)s.")
            % {"entry": label, "start": entry.start.isoformat(), "at": at.isoformat()}
        )


def check_fields(fields: dict, allowed: tuple[str, ...]) -> None:
    # Foreign keys may be given as objects ("weather") or raw keys ("weather_id").
    unknown = {name.removesuffix("_id") for name in fields} - set(allowed)
    if unknown:
        # A programming error in a caller, not bad user input.
        raise TypeError(f"unexpected fields {sorted(unknown)}")


def apply_fields(instance: Model, fields: dict, allowed: tuple[str, ...]) -> None:
    check_fields(fields, allowed)
    for name, value in fields.items():
        setattr(instance, name, value)
    instance.full_clean(exclude=[f.name for f in instance._meta.fields if f.name not in fields])
