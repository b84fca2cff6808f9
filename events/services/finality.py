"""Finalising a test event, and who may still change one that is final.

A final event refuses every change (:func:`require_amendable`); an
administrator may amend it but must give a reason, which the change history
keeps with every row the amendment writes (``events.history``).  Every
service that changes a record of an event calls :func:`require_amendable`
first, and the archive import for the rows it writes itself.
"""

from contextlib import contextmanager
from contextvars import ContextVar

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


# How a row finds its test event, by the parent it names (so that a row about
# to be added is checked as well as a stored one).
_EVENT_OF = (
    ("test_event_id", "pk"),  # shifts, test cases
    ("shift_id", "shifts"),  # legs, maps
    ("leg_id", "shifts__legs"),  # segments
    ("segment_id", "shifts__legs__segments"),  # notes, poses, images, snapshots
    ("test_case_id", "test_cases"),  # criteria
    ("criterion_id", "test_cases__criteria"),  # judgements
)


def require_amendable_row(instance) -> None:
    """:func:`require_amendable` for a row of a test event, stored or about to be."""
    if isinstance(instance, TestEvent):
        if instance.pk is not None:
            require_amendable(pk=instance.pk)
        return
    for attribute, path in _EVENT_OF:
        if (parent := getattr(instance, attribute, None)) is not None:
            require_amendable(**{path: parent})
            return


# Inside an archive import: the test events it makes final, whose contents
# arrive with their finalisation (exchange.importer).
_arriving: ContextVar[set] = ContextVar("finalised_by_import", default=frozenset())


@contextmanager
def finalisations_arriving():
    """While an archive import runs: the set it adds the test events to that the
    archive makes final here; their rows are written as the archive gives them."""
    arriving: set = set()
    token = _arriving.set(arriving)
    try:
        yield arriving
    finally:
        _arriving.reset(token)


def final_events(*conditions, **event_filter):
    """The final test events among those ``conditions`` and ``event_filter``
    find, whose contents refuse a change (an import's arriving ones aside).
    A write that must not wait for a statement of its own stores nothing
    while this finds a row (the storage port's single pose and GPS batch)
    and then asks :func:`require_amendable` why."""
    final = TestEvent.objects.filter(*conditions, **event_filter, finalised__isnull=False)
    if arriving := _arriving.get():
        final = final.exclude(pk__in=arriving)
    return final


def require_amendable(*conditions, **event_filter) -> None:
    """What a final test event refuses: anything added to it or changed in it
    (poses, local poses, maps, images, notes, judgements, segment and log
    edits, from operators, robots, the collector or an archive), unless an
    administrator amends it, giving a reason (``events.history.authored``);
    the change history lists the amendment.

    ``conditions`` and ``event_filter`` find the test events concerned."""
    final = final_events(*conditions, **event_filter)
    finalised = final.values_list("finalised", flat=True).first()
    if finalised is None:
        return
    since = {"date": f"{finalised:%Y-%m-%d %H:%M} UTC"}
    user = _acting_user()
    if user is None or not getattr(user, "is_authenticated", False):
        # The collector, an archive import, FTT itself: no one who could amend.
        raise RuleViolation(
            _("This test event is final since %(date)s; nothing is added to it or changed in it.")
            % since,
            code="final",
        )
    if not roles.has_role(user, roles.ADMINISTRATOR):
        raise PermissionDenied(
            _(
                "This test event is final since %(date)s; only an administrator may amend it, "
                "giving a reason."
            )
            % since
        )
    if not current_origin().reason.strip():
        raise ValidationError(
            {"reason": [_("This test event is final; an amendment needs a reason.")]}
        )
