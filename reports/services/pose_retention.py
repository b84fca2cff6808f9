"""The retention policy: poses of old shifts thinned to what the report draws.

Off unless ``FTT_POSE_RETENTION_MONTHS`` is set.  A shift whose newest pose is
older than that many months keeps, of each master's track, the points its map
in the report draws (``reports.charts.maps.map_tolerance``: half a pixel of the
shift's map, Douglas-Peucker as every drawing does); the others are deleted.
The per-segment figures were kept from every pose at write time and stay as
they are; a ThinnedSegment row marks the master, so a recount leaves it.  GPS fixes without a
position are not drawn and are kept (the figures count them apart).
"""

import logging
from datetime import datetime

import numpy as np
from dateutil.relativedelta import relativedelta
from django.conf import settings
from django.db import transaction
from django.db.models import Max
from django.utils import timezone

from events.models import Segment
from reports.charts.maps import Line, map_tolerance
from reports.documents.sections import OVERVIEW_SIZE
from telemetry.models import LocalPose, Pose, SegmentFigures, ThinnedSegment
from telemetry.selectors.track_drawing import simplified
from telemetry.storage import keys
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

log = logging.getLogger(__name__)

# Ids deleted per statement.
CHUNK = 5000


def old_shifts(months: int, now: datetime | None = None) -> list[int]:
    """Shifts not thinned yet whose newest pose is older than ``months`` months."""
    cutoff = (now or timezone.now()) - relativedelta(months=months)
    shifts = (
        SegmentFigures.objects.filter(segment__thinning__isnull=True)
        .values("segment__leg__shift")
        .annotate(newest=Max("last_stamp"))
        .filter(newest__lt=cutoff)
        .order_by("segment__leg__shift")
    )
    return [row["segment__leg__shift"] for row in shifts]


def thin_old_poses(months: int | None = None, now: datetime | None = None) -> int:
    """Thin the poses of every old shift (``months`` defaults to the setting;
    0 or None: nothing happens); returns how many poses were deleted."""
    months = settings.FTT_POSE_RETENTION_MONTHS if months is None else months
    if not months:
        return 0
    return sum(thin_shift(shift) for shift in old_shifts(months, now))


def _points(mode: str, master_ids: list[int]) -> dict[int, tuple[list, np.ndarray, np.ndarray]]:
    """(ids, x, y) of each master's drawn points, in driving order."""
    if mode == GPS_TRACK:
        rows = Pose.objects.filter(keys.USABLE_FIX, segment_id__in=master_ids)
        rows = rows.values_list("segment_id", "id", "point")
        split = [(seg, pk, p.x, p.y) for seg, pk, p in rows.order_by("segment_id", *_order())]
    else:
        rows = LocalPose.objects.filter(segment_id__in=master_ids)
        split = list(
            rows.values_list("segment_id", "id", "x", "y").order_by("segment_id", *_order())
        )
    tracks: dict[int, tuple[list, list, list]] = {}
    for seg, pk, x, y in split:
        ids, xs, ys = tracks.setdefault(seg, ([], [], []))
        ids.append(pk)
        xs.append(x)
        ys.append(y)
    return {seg: (ids, np.array(xs), np.array(ys)) for seg, (ids, xs, ys) in tracks.items()}


def _order():
    return keys.order_by()


def surviving_positions(x: np.ndarray, y: np.ndarray, tolerance: float) -> list[int]:
    """Positions of the points ``simplified`` keeps (it returns a subsequence of
    the points themselves, first and last included)."""
    kx, ky = simplified(x, y, tolerance)
    kept, j = [], 0
    for i in range(len(x)):
        if j < len(kx) and x[i] == kx[j] and y[i] == ky[j]:
            kept.append(i)
            j += 1
    return kept if j == len(kx) and kept else list(range(len(x)))


@transaction.atomic
def thin_shift(shift_id: int) -> int:
    """Thin one shift's stored poses to its report map; returns how many were deleted."""
    masters = list(
        Segment.objects.filter(leg__shift_id=shift_id, parent=None).values_list("pk", flat=True)
    )
    deleted = surviving_total = 0
    for mode, model in ((GPS_TRACK, Pose), (LOCAL_TRACK, LocalPose)):
        tracks = _points(mode, masters)
        if not tracks:
            continue
        lines = [Line(x, y, "0,0,0") for _ids, x, y in tracks.values()]
        tolerance, drawn = map_tolerance(mode, lines, OVERVIEW_SIZE)
        for (seg, (ids, _x, _y)), line in zip(tracks.items(), drawn, strict=True):
            keep = set(surviving_positions(np.asarray(line.x), np.asarray(line.y), tolerance))
            drop = [pk for i, pk in enumerate(ids) if i not in keep]
            surviving_total += len(keep)
            for begin in range(0, len(drop), CHUNK):
                model.objects.filter(segment_id=seg, id__in=drop[begin : begin + CHUNK]).delete()
            deleted += len(drop)
    ThinnedSegment.objects.bulk_create(
        [ThinnedSegment(segment_id=pk) for pk in masters], ignore_conflicts=True
    )
    log.info(
        "retention: shift %s thinned, %s poses deleted, %s kept", shift_id, deleted, surviving_total
    )
    return deleted
