"""Which segment rows one change touched, for readers that redraw only those, and
where a single pose goes."""

from django.db.models import Q

from common.memo import Expiring
from events.models import Segment

# segment id -> its master, with the master's leg and shift.  What is used of
# them does not change while the segment exists (a master's parent, leg, shift,
# test event, vehicle and mode are set when it opens); a deleted segment is
# noticed by the writer, whose statement finds no row.  Cached a minute in case
# an administrator edits a mode by hand in another process.
_pose_targets = Expiring(60.0)


def pose_target(segment_id: int) -> Segment | None:
    """The master segment a pose sent to ``segment_id`` is stored on, with its leg
    and shift loaded; None for an unknown id.  Cached per process (one query per
    segment, not per pose)."""
    master = _pose_targets.get(segment_id)
    if master is None:
        segment = (
            Segment.objects.select_related("leg__shift", "parent__leg__shift")
            .filter(pk=segment_id)
            .first()
        )
        if segment is None:
            return None
        master = segment.master
        _pose_targets.put(segment_id, master)
    return master


def forget_pose_targets(*args, **kwargs) -> None:
    _pose_targets.clear()


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
