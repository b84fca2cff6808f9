"""What a segment is called: the same words in the GUI, the report, the CSV and the API.

Master segments are numbered per leg in driving order (start, then id), so
the numbers stay readable however many legs a test event has: "Leg 2 · #7".
An ITO reason (child) is numbered under its master: "Leg 2 · #7.1".  The
database id stays a technical detail.

The database numbers them (window functions, one query per call): masters
per leg, reasons per master, in driving order.  Only the rows the numbers
need are read: the masters of the chosen segments' legs and the reasons of
their masters; the masters' window reads the partial index
``segment_master_order`` in its own order.
"""

from django.db.models import BooleanField, Case, ExpressionWrapper, F, Q, QuerySet, When, Window
from django.db.models.functions import RowNumber
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from events.models import Segment


def numbers_of(segments: QuerySet) -> dict[int, tuple[int, str]]:
    """{segment id: (its leg's number, its number "7" or "7.1")} for the segments
    of a queryset, each numbered among every segment of its leg; one query."""
    chosen = segments.order_by()
    # A filter on the rows would cut the windows short: the rows the numbers
    # need are read, and the chosen ones among them marked.
    rows = (
        Segment.objects.filter(
            Segment.IS_MASTER & Q(leg_id__in=chosen.values("leg_id"))
            | Q(parent_id__in=chosen.values("parent_id"))
        )
        .annotate(
            # Masters are numbered per leg, reasons per master.
            n=Window(
                RowNumber(),
                partition_by=[F("parent_id"), Case(When(Segment.IS_MASTER, then=F("leg_id")))],
                order_by=[F("start").asc(), F("id").asc()],
            ),
            chosen=ExpressionWrapper(Q(pk__in=chosen.values("pk")), output_field=BooleanField()),
        )
        .order_by()
        .values_list("pk", "parent_id", "leg__number", "n", "chosen")
    )
    masters, numbers = {}, {}
    for pk, parent, leg_number, n, picked in rows:
        if parent is None:
            masters[pk] = n
        if picked:
            numbers[pk] = (parent, leg_number, n)
    return {
        pk: (leg_number, _number(masters, parent, n))
        for pk, (parent, leg_number, n) in numbers.items()
    }


def _number(masters: dict[int, int], parent: int | None, n: int) -> str:
    """A master's own number, or a reason's under its master's ("?" for a
    master outside the chosen segments' legs)."""
    if parent is None:
        return str(n)
    return f"{masters.get(parent, '?')}.{n}"


def leg_numbers(leg_id: int) -> dict[int, str]:
    """{segment id: "7" or "7.1"} for every segment of one leg."""
    return {pk: n for pk, (_leg, n) in numbers_of(Segment.objects.filter(leg_id=leg_id)).items()}


def legs_numbers(leg_ids) -> dict[int, tuple[int, str]]:
    """{segment id: (its leg's number, its number)} for every segment of the given
    legs, in one query."""
    return numbers_of(Segment.objects.filter(leg_id__in=leg_ids))


_LABEL = gettext_noop("Leg %(leg)s · %(segment)s")


def label(leg_number: int, number: str) -> str:
    return _(_LABEL) % {"leg": leg_number, "segment": short_label(number)}


def short_label(number: str) -> str:
    """The label within its leg, where the leg is plain: "#7.1"."""
    return f"#{number}"


def segment_label(segment: Segment) -> str:
    """The label of one segment (one query)."""
    leg_number, number = numbers_of(Segment.objects.filter(pk=segment.pk))[segment.pk]
    return label(leg_number, number)


def segment_labels(segments: QuerySet) -> dict[int, str]:
    """{segment id: "Leg 2 · #7"} for the segments of a queryset; one query."""
    template = _(_LABEL)  # translated once, not per segment
    return {
        pk: template % {"leg": leg_number, "segment": short_label(number)}
        for pk, (leg_number, number) in numbers_of(segments).items()
    }
