"""Keeping each master segment's figures (telemetry.models.SegmentFigures) equal
to what its poses give, in the transaction that writes the poses.

A batch whose points all come after the stored last point in driving order (the
live case) adds its own length and the step from that point.  A late point or
batch (concurrent single poses committed out of order, an outage spool
replayed) replaces the step between its two neighbours in driving order, found
through the driving-order index, by the steps through its points.  Either way
the time depends on the new points, not on the track.  An import that merges
poses into a track measures it again (``measure_figures``).  The SQL of the
row and the neighbour reads is the storage port's (telemetry.storage).
"""

from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
from django.db.models import Max, Min
from django.db.models.functions import Coalesce

from common import uid_sums
from events import feed
from telemetry import storage
from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.selectors.distances import path_length
from telemetry.selectors.tracks import load_tracks
from telemetry.storage import keys
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK, TRACK_KINDS
from telemetry.storage.rows import Change, NewPoint

# Figures are float sums taken in another order than a measurement of the
# whole track: they may differ in the last bits, never by more than this.
TOLERANCE_M = 1e-6

# Sorts before every stamp: a point without the robot's clock comes last.
_NEVER = datetime(1, 1, 1, tzinfo=UTC)


def _model(mode):
    return Pose if mode == GPS_TRACK else LocalPose


def _key(robot_stamp, received, pk) -> tuple:
    """The driving order (telemetry.storage.keys) as a Python sort key."""
    return (robot_stamp is None, robot_stamp or _NEVER, received, pk)


def _usable(mode):
    return keys.usable(_model(mode).objects.all(), mode)


_UNREAD = object()


@dataclass
class Added:
    """What a write added to a track: its usable points in driving order, and
    whether they all follow the points stored before them (a live batch) or some
    fall between them (a late one), which changes the track inside."""

    points: list[NewPoint]
    appended: bool


def add_to_figures(
    master_id: int, mode: str, new: list[NewPoint], seen=_UNREAD, announce=None
) -> Added:
    """Add the points just stored on ``master_id`` (the storage port's answer) to its
    figures, in time that depends on the new points, not on the track: an
    upsert, after a read of the row unless the caller gives what it read
    (``seen``, storage.StoredFigures or None).  Call inside the transaction that
    stored them; from then on the figures row is locked until the commit, so
    concurrent writers of one master learn in commit order where their points lie.
    ``announce`` gives the change-feed row of what was added (``Added``,
    unsaved, or None), which the storage port writes with the figures: the
    lock orders the feed rows of one master as their commits."""
    if not new:
        return Added([], True)
    rows = sorted((p for p in new if p.usable), key=lambda p: _key(p.robot_stamp, p.received, p.id))
    alone = _alone(new, rows, mode)
    if seen is _UNREAD:
        seen = storage.read_stored_figures(master_id, mode)
    for _attempt in range(2):
        added = Added(rows, _appends(rows, seen))
        feed_row = announce(added) if announce is not None else None
        change = _change(master_id, mode, rows, alone, seen)
        applied, written = storage.write_change(master_id, mode, seen, change, feed_row)
        if applied:
            if feed_row is not None:
                feed.settle(feed_row)
            return added
        # Another writer changed the row since it was read; it is locked now.
        seen = written
    raise RuntimeError(f"the figures of segment {master_id} changed under their lock")


def _appends(rows: list[NewPoint], seen) -> bool:
    """Whether the sorted usable ``rows`` all come after the last point ``seen``
    (storage.StoredFigures or None) holds, in driving order."""
    if not rows or seen is None or not seen.points:
        return True
    first = _key(rows[0].robot_stamp, rows[0].received, rows[0].id)
    return first > _key(seen.last_robot_stamp, seen.last_received, seen.last_id)


def _alone(new: list[NewPoint], rows: list[NewPoint], mode: str) -> dict:
    """The figures of the ``new`` points by themselves (``rows``: the usable
    ones, sorted)."""
    alone = dict.fromkeys(keys.FIGURE_FIELDS)
    alone.update(
        points=len(rows),
        no_fix=len(new) - len(rows),
        length=0.0,
        uid_sum=uid_sums.combined(uid_sums.uid_sum(p.uid for p in new)),
    )
    if not rows:
        return alone
    x = np.array([r.x for r in rows], dtype=float)
    y = np.array([r.y for r in rows], dtype=float)
    stamps = [r.robot_stamp or r.received for r in rows]
    first, last = rows[0], rows[-1]
    alone.update(
        length=path_length(x, y, mode),
        first_x=first.x, first_y=first.y, last_x=last.x, last_y=last.y,
        last_robot_stamp=last.robot_stamp, last_received=last.received, last_id=last.id,
        first_stamp=min(stamps), last_stamp=max(stamps),
        min_x=float(x.min()), min_y=float(y.min()), max_x=float(x.max()), max_y=float(y.max()),
    )  # fmt: skip
    return alone


def _change(master_id, mode, rows: list[NewPoint], alone: dict, seen) -> storage.Change:
    """What ``rows`` change in the figures that hold ``seen``: an appended batch
    adds its length and the step from the stored last point; a late one replaces
    the step between its neighbours in driving order with the steps through it."""
    uids = uid_sums.combined(uid_sums.EMPTY if seen is None else seen.uid_sum, alone["uid_sum"])
    if not rows:
        return Change(alone, 0.0, False, False, uids)
    if seen is None or not seen.points:
        return Change(alone, alone["length"], True, True, uids)
    if _appends(rows, seen):
        join = path_length([seen.last_x, rows[0].x], [seen.last_y, rows[0].y], mode)
        return Change(alone, alone["length"] + join, False, True, uids)
    first = (rows[0].robot_stamp, rows[0].received, rows[0].id)
    last = (rows[-1].robot_stamp, rows[-1].received, rows[-1].id)
    before, after = storage.neighbours(master_id, mode, first, last)
    inside = (
        storage.points_between(master_id, mode, first, last)
        if len(rows) > 1
        else [(rows[0].id, rows[0].x, rows[0].y)]
    )
    merged = [p for p in (before, *inside, after) if p is not None]
    new_ids = {r.id for r in rows}
    old = [p for p in merged if p[0] not in new_ids]
    length = _length(merged, mode) - _length(old, mode)
    return Change(alone, length, before is None, after is None, uids)


def _length(points: list[tuple], mode: str) -> float:
    return path_length([p[1] for p in points], [p[2] for p in points], mode)


@dataclass
class _Measured:
    length: float
    points: int
    no_fix: int
    x: np.ndarray
    y: np.ndarray
    uid_sum: str = uid_sums.EMPTY


def _measured(master_ids: list[int], mode: str) -> dict[int, _Measured]:
    """The figures' track part and uid sum, measured from the poses by the
    distance rule."""
    found = {
        pk: _Measured(path_length(t.x, t.y, mode), len(t), t.no_fix, t.x, t.y)
        for pk, t in load_tracks(master_ids, mode, within_stored_span=False).items()
    }
    for pk, total in _uid_sums(master_ids, mode).items():
        if pk not in found:
            found[pk] = _Measured(0.0, 0, 0, np.empty(0), np.empty(0))
        found[pk].uid_sum = total
    return found


def _uid_sums(master_ids: list[int] | None, mode: str) -> dict[int, str]:
    """The uid sum of each master's poses (None: of every master); masters
    without poses are absent."""
    sums = defaultdict(int)
    rows = _model(mode).objects.all()
    if master_ids is not None:
        rows = rows.filter(segment_id__in=master_ids)
    for pk, uid in rows.values_list("segment_id", "uid").iterator(chunk_size=20000):
        sums[pk] += uid_sums.uid_value(uid)
    return {pk: uid_sums.combined(total) for pk, total in sums.items()}


def _measure(figures: SegmentFigures, measured=_UNREAD) -> None:
    """Set every figure of ``figures`` from its segment's poses (``measured``: its
    track part when the caller read it, None for a segment without poses)."""
    master_id, mode = figures.segment_id, figures.mode
    if measured is _UNREAD:
        measured = _measured([master_id], mode).get(master_id)
    empty = measured is None or measured.points == 0
    figures.points = 0 if measured is None else measured.points
    figures.no_fix = 0 if measured is None else measured.no_fix
    figures.uid_sum = uid_sums.EMPTY if measured is None else measured.uid_sum
    figures.length = 0.0 if empty else measured.length
    usable = _usable(mode).filter(segment_id=master_id)
    last = (
        None
        if empty
        else usable.order_by(*keys.reverse_order_by())
        .values_list("robot_stamp", "received", "id")
        .first()
    )
    figures.last_robot_stamp, figures.last_received, figures.last_id = last or (None, None, None)
    span = usable.aggregate(
        first=Min(Coalesce("robot_stamp", "received")),
        last=Max(Coalesce("robot_stamp", "received")),
    )
    figures.first_stamp, figures.last_stamp = span["first"], span["last"]
    if empty:
        figures.first_x = figures.first_y = figures.last_x = figures.last_y = None
        figures.min_x = figures.min_y = figures.max_x = figures.max_y = None
        return
    x, y = measured.x, measured.y
    figures.first_x, figures.first_y = float(x[0]), float(y[0])
    figures.last_x, figures.last_y = float(x[-1]), float(y[-1])
    figures.min_x, figures.min_y = float(x.min()), float(y.min())
    figures.max_x, figures.max_y = float(x.max()), float(y.max())


def measure_figures(master_ids: Iterable[int], modes=TRACK_KINDS) -> None:
    """Measure the figures of ``master_ids`` from their poses again (after an
    import merged poses into them).  Call inside the writing transaction."""
    for mode in modes:
        for master_id in sorted(set(master_ids)):
            figures = storage.locked_figures(master_id, mode)
            _measure(figures)
            figures.save()


def sum_uids_again() -> None:
    """Set the uid sum of every stored figures row from the poses stored, and
    nothing else (figures kept before they kept a sum, thinned ones too), in
    one pass over each pose table."""
    for mode in TRACK_KINDS:
        sums = _uid_sums(None, mode)
        rows = list(SegmentFigures.objects.filter(mode=mode))
        for figures in rows:
            figures.uid_sum = sums.get(figures.segment_id, uid_sums.EMPTY)
        SegmentFigures.objects.bulk_update(rows, ["uid_sum"], batch_size=500)


# The figures a recount compares, and how.
_EXACT = (
    "points", "no_fix", "first_x", "first_y", "last_x", "last_y", "last_robot_stamp",
    "last_received", "last_id", "first_stamp", "last_stamp", "min_x", "min_y", "max_x", "max_y",
    "uid_sum",
)  # fmt: skip


def differences(kept: SegmentFigures | None, fresh: SegmentFigures) -> list[str]:
    """Where the stored figures differ from freshly measured ones ("length: 1.0 != 2.0")."""
    found = []
    for name in ("length", *_EXACT):
        was = getattr(kept, name) if kept is not None else getattr(SegmentFigures(), name)
        now = getattr(fresh, name)
        if name == "length":
            same = abs((was or 0.0) - (now or 0.0)) <= TOLERANCE_M
        else:
            same = was == now
        if not same:
            found.append(f"{name}: {was!r} != {now!r}")
    return found


def recount_figures(
    master_ids: list[int], *, fix: bool = False
) -> dict[tuple[int, str], list[str]]:
    """{(segment id, mode): differences} between the stored figures of the given
    masters and their poses; with ``fix``, the stored figures are set right."""
    found = {}
    kept = {
        (f.segment_id, f.mode): f for f in SegmentFigures.objects.filter(segment_id__in=master_ids)
    }
    for mode in (GPS_TRACK, LOCAL_TRACK):
        measured = _measured(master_ids, mode)
        for master_id in master_ids:
            fresh = SegmentFigures(segment_id=master_id, mode=mode)
            _measure(fresh, measured.get(master_id))
            was = kept.get((master_id, mode))
            if was is None and fresh.points == 0 and fresh.no_fix == 0:
                continue
            diff = differences(was, fresh)
            if diff:
                found[(master_id, mode)] = diff
                if fix:
                    if was is not None:
                        fresh.pk = was.pk
                    fresh.save()
    return found
