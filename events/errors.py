"""Errors raised by the service layer when a request breaks a rule.

They carry field messages so that every caller (API, GUI, admin, collector)
can tell a person what to change.
"""

from django.core.exceptions import ValidationError


class RuleViolation(ValidationError):
    """The request is well-formed but the current state forbids it (HTTP 409)."""


class NotFound(ValidationError):
    """A referenced row does not exist."""
