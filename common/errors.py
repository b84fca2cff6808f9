"""Errors raised by the service layer when a request breaks a rule.

They carry field messages so that every caller (API, GUI, admin, collector)
can tell a person what to change.
"""

from collections import Counter

from django.core.exceptions import ValidationError
from django.db.models import ProtectedError, RestrictedError
from django.utils.translation import gettext as _


class RuleViolation(ValidationError):
    """The request is well-formed but the current state forbids it (HTTP 409)."""


class NotFound(ValidationError):
    """A referenced row does not exist."""


class TooManyWaiting(ValidationError):
    """The caller already has as many jobs waiting as it may (HTTP 429, Retry-After)."""

    retry_after = 30


def describe_protected(exc: ProtectedError | RestrictedError) -> str:
    blockers = list(getattr(exc, "protected_objects", None) or exc.restricted_objects)
    counts = Counter(type(obj)._meta.verbose_name_plural for obj in blockers)
    examples = ", ".join(str(obj) for obj in blockers[:3])
    where = ", ".join(f"{n} {name}" for name, n in counts.items())
    more = "" if len(blockers) <= 3 else ", …"
    return _("Still in use by %(where)s (%(examples)s); change or delete those first.") % {
        "where": where,
        "examples": examples + more,
    }
