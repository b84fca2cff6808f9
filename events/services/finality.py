"""Finalising a test event, and who may still change one that is final.

A final event is read-only for operators; an administrator may amend it but
must give a reason, which the change history keeps with every row the
amendment writes (``events.history``).  Every service that changes a record
of an event calls :func:`require_amendable` first.
"""

from django.core.exceptions import PermissionDenied, ValidationError
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext as _

from common import roles
from common.errors import RuleViolation
from events.feed import announce_and_return
from events.history import current_origin
from events.models import TestEvent
from events.selectors.taxonomy import current_taxonomy
from events.services.common import lock

FINALISE_PERMISSION = "events.finalise_testevent"


def may_finalise(user) -> bool:
    """Administrators, and people given the "finalise" permission (e.g. a test director)."""
    return roles.has_role(user, roles.ADMINISTRATOR) or (
        roles.has_role(user, roles.OPERATOR) and user.has_perm(FINALISE_PERMISSION)
    )


def _acting_user():
    origin = current_origin()
    return origin.user or getattr(origin.request, "user", None)


@transaction.atomic
def finalise_test_event(event: TestEvent, *, by=None) -> TestEvent:
    """Freeze a closed event: its taxonomy is copied and it becomes read-only."""
    by = by if by is not None else _acting_user()
    if by is not None and not may_finalise(by):
        raise PermissionDenied(
            _("Only an administrator or someone allowed to finalise may finalise a test event.")
        )
    event = lock(event)
    if event.end is None:
        raise RuleViolation(_("Close the test event before finalising it."), code="open")
    if event.finalised is not None:
        raise RuleViolation(_("This test event is already final."), code="final")
    event.finalised = timezone.now()
    event.finalised_by = by.get_username() if by is not None else ""
    event.taxonomy = current_taxonomy()
    # Dated like the finalisation itself, so it is not listed as an amendment after it.
    event._history_date = event.finalised
    event.save(update_fields=["finalised", "finalised_by", "taxonomy"])
    return announce_and_return(event)


# How a row of each kind finds its test event.
_EVENT_OF = {
    "testevent": "pk",
    "shift": "shifts",
    "leg": "shifts__legs",
    "segment": "shifts__legs__segments",
}


def require_amendable_row(instance) -> None:
    """:func:`require_amendable` for a test event, shift, leg, segment, note or image."""
    name = instance._meta.model_name
    if name in _EVENT_OF:
        require_amendable(**{_EVENT_OF[name]: instance.pk})
    elif hasattr(instance, "segment_id"):
        require_amendable(shifts__legs__segments=instance.segment_id)


def require_amendable(**event_filter) -> None:
    """Refuse a change to the final event ``event_filter`` finds unless an
    administrator gives a reason (``events.history.authored``).

    Writes without a person (imports, FTT itself) pass: they carry what was
    recorded elsewhere, and the history names their channel."""
    finalised = TestEvent.objects.filter(**event_filter).values_list("finalised", flat=True).first()
    if finalised is None:
        return
    user = _acting_user()
    if user is None or not getattr(user, "is_authenticated", False):
        return
    if not roles.has_role(user, roles.ADMINISTRATOR):
        raise PermissionDenied(
            _(
                "This test event is final since %(date)s; only an administrator may amend it, "
                "giving a reason."
            )
            % {"date": f"{finalised:%Y-%m-%d %H:%M} UTC"}
        )
    if not current_origin().reason.strip():
        raise ValidationError(
            {"reason": [_("This test event is final; an amendment needs a reason.")]}
        )
