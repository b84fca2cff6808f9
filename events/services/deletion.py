"""Deleting rows: hierarchy rows take everything below with them (files are
removed by django-cleanup once the transaction commits); configuration rows
that are still referenced are refused with a message saying where."""

from django.db import transaction
from django.db.models import Model, ProtectedError, RestrictedError
from django.dispatch import Signal
from django.utils.translation import gettext as _

from common.errors import RuleViolation, describe_protected
from events.feed import announce_row
from events.services.finality import require_amendable_row

# Sent inside the deleting transaction once ``instance`` is deleted: an app that
# keeps figures from such rows measures them again (telemetry's poses).
deleted = Signal()


@transaction.atomic
def delete(instance: Model) -> None:
    require_amendable_row(instance)
    try:
        announce_row(instance, deleted=True)
        instance.delete()
        deleted.send(sender=type(instance), instance=instance)
    except (ProtectedError, RestrictedError) as exc:
        raise RuleViolation(
            _("Cannot delete '%(row)s': %(why)s")
            % {"row": instance, "why": describe_protected(exc)}
        ) from None
