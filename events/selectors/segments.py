"""Which segment rows one change touched, for readers that redraw only those."""

from django.db.models import Q

from events.models import Segment


def touched_by(segment_ids) -> dict[int, list[Segment]]:
    """{announced segment id: the rows its change touched}, in two queries.

    A mode switch announces only the new master, but it also closed the
    previous master and its reasons (they end where the new one starts) and
    opened a reason under it; closing a master closes its reasons.  Segments
    deleted since are absent.
    """
    announced = {s.pk: s for s in Segment.objects.filter(pk__in=set(segment_ids))}
    if not announced:
        return {}
    candidates = list(
        Segment.objects.filter(leg_id__in={s.leg_id for s in announced.values()}).filter(
            Q(pk__in=list(announced))
            | Q(parent_id__in=list(announced))
            | Q(end__in=[s.start for s in announced.values()])
        )
    )
    return {
        pk: [c for c in candidates if _touched(c, segment)] for pk, segment in announced.items()
    }


def _touched(row: Segment, announced: Segment) -> bool:
    return row.leg_id == announced.leg_id and (
        row.pk == announced.pk or row.parent_id == announced.pk or row.end == announced.start
    )
