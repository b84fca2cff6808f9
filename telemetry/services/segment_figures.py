"""Keeping each master segment's figures (telemetry.models.SegmentFigures) equal
to what its poses give, in the transaction that writes the poses.

A batch whose points all come after the kept last point in driving order (the
live case) is appended: its steps are measured and added, in time that depends
on the batch, not on the segment.  Anything else (a late batch from an outage
spool, an import merged into a track) measures the segment's track again.
The figures row is locked first, so two writers on one segment take turns,
and the second sees the first's poses when it measures.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
from django.db.models import Max, Min
from django.db.models.functions import Coalesce

from telemetry.models import LocalPose, Pose, SegmentFigures
from telemetry.models.poses import FixStatus
from telemetry.selectors import driving_order
from telemetry.selectors.distances import path_length
from telemetry.selectors.tracks import GPS, LOCAL, MODES, load_tracks
from telemetry.services.pose_rows import NewPoint

# Figures are float sums taken in another order than a measurement of the
# whole track: they may differ in the last bits, never by more than this.
TOLERANCE_M = 1e-6

# Sorts before every stamp: a point without the robot's clock comes last.
_NEVER = datetime(1, 1, 1, tzinfo=UTC)


def _model(mode):
    return Pose if mode == GPS else LocalPose


def _key(robot_stamp, received, pk) -> tuple:
    """The driving order (telemetry.selectors.driving_order) as a Python sort key."""
    return (robot_stamp is None, robot_stamp or _NEVER, received, pk)


def _usable(mode):
    rows = _model(mode).objects.all()
    return rows.exclude(fix_status=FixStatus.NO_FIX) if mode == GPS else rows


# Creates the row or takes it as it is, and locks it either way (an upsert
# locks the row it meets), in one statement.
_LOCK = """
INSERT INTO {table} (segment_id, mode, points, no_fix, length) VALUES (%s, %s, 0, 0, 0)
ON CONFLICT (segment_id, mode) DO UPDATE SET mode = excluded.mode
RETURNING *
"""


def _locked(master_id: int, mode: str) -> SegmentFigures:
    query = _LOCK.format(table=SegmentFigures._meta.db_table)
    return next(iter(SegmentFigures.objects.raw(query, [master_id, mode])))


def keep_figures(master_id: int, mode: str, new: list[NewPoint]) -> None:
    """Add the points just stored on ``master_id`` (pose_rows' answer) to its
    figures: two statements, whatever the size of the batch or the segment.
    Call inside the transaction that stored them."""
    if not new:
        return
    figures = _locked(master_id, mode)
    rows = sorted((p for p in new if p.usable), key=lambda p: _key(p.robot_stamp, p.received, p.id))
    last = (figures.last_robot_stamp, figures.last_received, figures.last_id)
    if (
        rows
        and figures.points
        and _key(rows[0].robot_stamp, rows[0].received, rows[0].id) <= _key(*last)
    ):
        _measure(figures)
    else:
        figures.no_fix += len(new) - len(rows)
        if rows:
            _append(figures, rows, mode)
    figures.save()


def _append(figures: SegmentFigures, rows: list[NewPoint], mode: str) -> None:
    x = np.array([r.x for r in rows], dtype=float)
    y = np.array([r.y for r in rows], dtype=float)
    stamps = [r.robot_stamp or r.received for r in rows]
    if figures.points:
        figures.length += path_length(
            np.concatenate(([figures.last_x], x)), np.concatenate(([figures.last_y], y)), mode
        )
    else:
        figures.length = path_length(x, y, mode)
        figures.first_x, figures.first_y = float(x[0]), float(y[0])
    figures.points += len(rows)
    figures.last_x, figures.last_y = float(x[-1]), float(y[-1])
    figures.last_robot_stamp, figures.last_received, figures.last_id = (
        rows[-1][2],
        rows[-1][3],
        rows[-1].id,
    )
    figures.first_stamp = min(filter(None, [figures.first_stamp, *stamps]))
    figures.last_stamp = max(filter(None, [figures.last_stamp, *stamps]))
    figures.min_x = float(min(x.min(), figures.min_x if figures.min_x is not None else np.inf))
    figures.min_y = float(min(y.min(), figures.min_y if figures.min_y is not None else np.inf))
    figures.max_x = float(max(x.max(), figures.max_x if figures.max_x is not None else -np.inf))
    figures.max_y = float(max(y.max(), figures.max_y if figures.max_y is not None else -np.inf))


@dataclass
class _Measured:
    length: float
    points: int
    no_fix: int
    x: np.ndarray
    y: np.ndarray


def _measured(master_ids: list[int], mode: str) -> dict[int, _Measured]:
    """The figures' track part, measured from the poses by the distance rule."""
    return {
        pk: _Measured(path_length(t.x, t.y, mode), len(t), t.no_fix, t.x, t.y)
        for pk, t in load_tracks(master_ids, mode).items()
    }


_UNREAD = object()


def _measure(figures: SegmentFigures, measured=_UNREAD) -> None:
    """Set every figure of ``figures`` from its segment's poses (``measured``: its
    track part when the caller read it, None for a segment without poses)."""
    master_id, mode = figures.segment_id, figures.mode
    if measured is _UNREAD:
        measured = _measured([master_id], mode).get(master_id)
    empty = measured is None or measured.points == 0
    figures.points = 0 if measured is None else measured.points
    figures.no_fix = 0 if measured is None else measured.no_fix
    figures.length = 0.0 if empty else measured.length
    usable = _usable(mode).filter(segment_id=master_id)
    last = (
        None
        if empty
        else usable.order_by(*(o.copy().reverse_ordering() for o in driving_order.order_by()))
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


def measure_figures(master_ids: Iterable[int], modes=MODES) -> None:
    """Measure the figures of ``master_ids`` from their poses again (after an
    import merged poses into them).  Call inside the writing transaction."""
    for mode in modes:
        for master_id in sorted(set(master_ids)):
            figures = _locked(master_id, mode)
            _measure(figures)
            figures.save()


# The figures a recount compares, and how.
_EXACT = (
    "points", "no_fix", "first_x", "first_y", "last_x", "last_y", "last_robot_stamp",
    "last_received", "last_id", "first_stamp", "last_stamp", "min_x", "min_y", "max_x", "max_y",
)  # fmt: skip


def differences(kept: SegmentFigures | None, fresh: SegmentFigures) -> list[str]:
    """Where the kept figures differ from freshly measured ones ("length: 1.0 != 2.0")."""
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
    """{(segment id, mode): differences} between the kept figures of the given
    masters and their poses; with ``fix``, the kept figures are set right."""
    found = {}
    kept = {
        (f.segment_id, f.mode): f for f in SegmentFigures.objects.filter(segment_id__in=master_ids)
    }
    for mode in (GPS, LOCAL):
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
