"""What a segment is called: the same words in the GUI, the report, the CSV and the API.

Master segments are numbered per leg in driving order (start, then id), so
the numbers stay readable however many legs a test event has: "Leg 2 · #7".
An ITO reason (child) is numbered under its master: "Leg 2 · #7.1".  The
database id stays a technical detail.
"""

from collections import defaultdict

from django.utils.translation import gettext as _

from events.models import Segment


def leg_numbers(leg_id: int) -> dict[int, str]:
    """{segment id: "7" or "7.1"} for every segment of one leg."""
    rows = (
        Segment.objects.filter(leg_id=leg_id).order_by("start", "id").values_list("id", "parent_id")
    )
    return numbers(rows)


def legs_numbers(leg_ids) -> dict[int, tuple[int, str]]:
    """{segment id: (its leg's number, its number)} for every segment of the given
    legs, in one query."""
    rows = (
        Segment.objects.filter(leg_id__in=leg_ids)
        .order_by("leg_id", "start", "id")
        .values_list("leg_id", "leg__number", "id", "parent_id")
    )
    by_leg: dict[tuple[int, int], list] = defaultdict(list)
    for leg_id, leg_number, pk, parent in rows:
        by_leg[(leg_id, leg_number)].append((pk, parent))
    return {
        pk: (leg_number, n)
        for (_, leg_number), pairs in by_leg.items()
        for pk, n in numbers(pairs).items()
    }


def numbers(rows) -> dict[int, str]:
    """Numbers of one leg's segments from (id, parent id) pairs in driving order."""
    result: dict[int, str] = {}
    children: dict[int, int] = defaultdict(int)
    masters = 0
    pending = []
    for pk, parent in rows:
        if parent is None:
            masters += 1
            result[pk] = str(masters)
        else:
            pending.append((pk, parent))
    for pk, parent in pending:
        children[parent] += 1
        result[pk] = f"{result.get(parent, '?')}.{children[parent]}"
    return result


def label(leg_number: int, number: str) -> str:
    return _("Leg %(leg)s · %(segment)s") % {"leg": leg_number, "segment": short_label(number)}


def short_label(number: str) -> str:
    """The label within its leg, where the leg is plain: "#7.1"."""
    return f"#{number}"


def segment_label(segment: Segment) -> str:
    """The label of one segment (one query for its leg's numbering)."""
    return label(segment.leg.number, leg_numbers(segment.leg_id)[segment.pk])


def segment_labels(segments: list[Segment]) -> dict[int, str]:
    """{segment id: "Leg 2 · #7"} for segments ordered by leg, then start and id."""
    rows: dict[int, list[tuple[int, int | None]]] = defaultdict(list)
    legs = {}
    for s in segments:
        rows[s.leg_id].append((s.id, s.parent_id))
        legs[s.leg_id] = s.leg.number
    return {
        pk: label(legs[leg_id], number)
        for leg_id, pairs in rows.items()
        for pk, number in numbers(pairs).items()
    }
