"""What a test event's report shows besides its statistics: its shifts with their
people, the legs with their weather, notes, camera images and the ITO reasons."""

from collections import defaultdict

from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from common.deferred_text import DeferredText, deferred
from events.models import ItoReason, Leg, Note, Segment, Shift, TestEvent
from events.selectors.taxonomy import taxonomy_of
from reports.selectors.statistics import segment_scope
from telemetry.models import Image


def has_segments(event: TestEvent, *, shift: int | None = None, leg: int | None = None) -> bool:
    return Segment.objects.filter(**segment_scope(event, shift=shift, leg=leg)).exists()


def report_scope(
    event: TestEvent, *, shift: int | None = None, leg: int | None = None
) -> tuple[int | None, int | None]:
    """(shift id, leg id) of a report of the whole test event, one shift or one
    leg; a leg brings its shift.  Raises ``ValueError`` with {field: [message]}
    for a shift or leg that is not part of this test event."""
    if leg is not None:
        leg_shift = (
            Leg.objects.filter(pk=leg, shift__test_event=event)
            .values_list("shift_id", flat=True)
            .first()
        )
        if leg_shift is None:
            message = _("Leg %(leg)s is not part of test event %(event)s.")
            raise ValueError({"leg": [message % {"leg": leg, "event": event.pk}]})
        if shift is not None and shift != leg_shift:
            message = _("Leg %(leg)s is not part of shift %(shift)s.")
            raise ValueError({"leg": [message % {"leg": leg, "shift": shift}]})
        return leg_shift, leg
    if shift is not None and not event.shifts.filter(pk=shift).exists():
        message = _("Shift %(shift)s is not part of test event %(event)s.")
        raise ValueError({"shift": [message % {"shift": shift, "event": event.pk}]})
    return shift, None


def reasons_by_key(event: TestEvent) -> dict[str, ItoReason]:
    """The reasons with the names and colours the event's report uses: a final
    event's frozen taxonomy (events.selectors.taxonomy), else the catalogue."""
    return {
        key: ItoReason(
            key=key,
            short_description=entry["name"],
            color=entry["color"],
            counts_as_intervention=entry["counts"],
        )
        for key, entry in taxonomy_of(event).items()
    }


def scope_text(*, shift: int | None = None, leg: int | None = None) -> DeferredText:
    """What a report covers, as words a job's row keeps: "Shift 2 · Leg 1"."""
    if leg is not None:
        row = Leg.objects.select_related("shift").filter(pk=leg).first()
        if row is None:
            return deferred(gettext_noop("a deleted leg"))
        return deferred(
            gettext_noop("Shift %(shift)s · Leg %(leg)s"), shift=row.shift.number, leg=row.number
        )
    if shift is not None:
        row = Shift.objects.filter(pk=shift).first()
        if row is None:
            return deferred(gettext_noop("a deleted shift"))
        return deferred(gettext_noop("Shift %(shift)s"), shift=row.number)
    return deferred(gettext_noop("Test event"))


def scope_name(*, shift: int | None = None, leg: int | None = None) -> str:
    """What a report covers, in the active language."""
    return str(scope_text(shift=shift, leg=leg))


def shifts_of(event: TestEvent, shift: int | None = None) -> list[Shift]:
    """In time order, with vehicle, performer and people; only ``shift`` if given."""
    shifts = event.shifts.filter(pk=shift) if shift is not None else event.shifts.all()
    return list(
        shifts.select_related(
            "vehicle",
            "performer",
            "test_director",
            "test_administrator",
            "safety_officer",
            "robot_operator",
        ).order_by("start", "id")
    )


def legs_by_shift(shifts: list[Shift], leg: int | None = None) -> dict[int, list[Leg]]:
    """{shift id: its legs in time order, with their weather}; every shift a key;
    only ``leg`` if given."""
    grouped = {shift.id: [] for shift in shifts}
    legs = Leg.objects.filter(shift__in=shifts)
    if leg is not None:
        legs = legs.filter(pk=leg)
    for leg_row in legs.select_related("weather").order_by("start", "id"):
        grouped[leg_row.shift_id].append(leg_row)
    return grouped


def notes_by_master(event: TestEvent, **scope) -> dict[int, list[Note]]:
    """{master segment id: the notes on it and on its ITO children}, oldest first
    (``scope``: shift or leg, as in :func:`segment_scope`)."""
    grouped = defaultdict(list)
    for note in (
        Note.objects.filter(**segment_scope(event, **scope, via="segment__"))
        .select_related("author", "segment")
        .order_by("created", "id")
    ):
        grouped[note.segment.master_id].append(note)
    return grouped


def images_by_segment(event: TestEvent, **scope) -> dict[int, list[Image]]:
    """{segment id: its camera images}, in the order they were taken (``scope``:
    shift or leg, as in :func:`segment_scope`)."""
    grouped = defaultdict(list)
    for image in Image.objects.filter(**segment_scope(event, **scope, via="segment__")).order_by(
        "robot_stamp", "received", "id"
    ):
        grouped[image.segment_id].append(image)
    return grouped
