"""Deleting rows: hierarchy rows take everything below with them (files are
removed by django-cleanup once the transaction commits); configuration rows
that are still referenced are refused with a message saying where."""

from collections import Counter

from django.db import transaction
from django.db.models import Model, ProtectedError, RestrictedError

from events.errors import RuleViolation
from rosbridge_app.live import announce_row


def describe_protected(exc: ProtectedError | RestrictedError) -> str:
    blockers = list(getattr(exc, "protected_objects", None) or exc.restricted_objects)
    counts = Counter(type(obj)._meta.verbose_name_plural for obj in blockers)
    examples = ", ".join(str(obj) for obj in blockers[:3])
    where = ", ".join(f"{n} {name}" for name, n in counts.items())
    more = "" if len(blockers) <= 3 else ", …"
    return f"Still in use by {where} ({examples}{more}); change or delete those first."


@transaction.atomic
def delete(instance: Model) -> None:
    try:
        announce_row(instance, deleted=True)
        instance.delete()
    except (ProtectedError, RestrictedError) as exc:
        raise RuleViolation(f"Cannot delete '{instance}': {describe_protected(exc)}") from None
