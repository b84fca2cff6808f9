"""Time-ordered track points of master segments, for distances, maps, the API and exports.

Points are in driving order (``telemetry.storage.keys``).  Fixes flagged "no fix" carry
no usable position and are dropped.  Drawing a track is ``track_drawing``'s
job, keeping tracks between the map's reads ``cached_tracks``'.
"""

from dataclasses import dataclass, field
from datetime import UTC, datetime

import numpy as np
from django.db.models import FloatField, Func, OuterRef, QuerySet, Subquery
from django.db.models.functions import Coalesce

from events.models import Segment
from telemetry import storage
from telemetry.models import Pose
from telemetry.storage.keys import GPS_TRACK, TRACK_KINDS, USABLE_FIX

# Two consecutive points further apart in time than this are reported as a gap.
GAP_SECONDS = 10.0


class Coordinate(Func):
    """ST_X / ST_Y of a point column as a plain float (no geometry object)."""

    output_field = FloatField()


@dataclass
class Track:
    """The usable points of one master segment, in driving order.

    ``x``/``y`` are longitude/latitude in GPS mode and map-frame metres in
    local mode; ``t`` is each point's time (robot clock, else arrival) in
    seconds since 1970.
    """

    segment_id: int
    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    frame: str = ""
    no_fix: int = 0
    # Thinned copies by tolerance (see ``thinned``).
    memo: dict = field(default_factory=dict, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.x)

    @property
    def stamps(self) -> list[datetime]:
        return [_instant(t) for t in self.t]

    @property
    def last_stamp(self) -> datetime | None:
        return _instant(self.t.max()) if len(self.t) else None

    @property
    def gaps(self) -> list[tuple[datetime, datetime]]:
        """Pairs of consecutive points further apart in time than GAP_SECONDS."""
        where = np.nonzero(np.diff(self.t) > GAP_SECONDS)[0]
        return [(_instant(self.t[i]), _instant(self.t[i + 1])) for i in where]


def load_tracks(
    segment_ids: list[int], mode: str = GPS_TRACK, *, within_stored_span: bool = True
) -> dict[int, Track]:
    """Tracks of the given master segments; segments without points are absent.

    The read is bounded by the span the segments' stored figures give (on
    PostgreSQL only the month partitions they span are read);
    ``within_stored_span=False`` reads every pose, for measuring the figures
    themselves (telemetry.services.segment_figures)."""
    if mode not in TRACK_KINDS:
        raise ValueError(f"mode must be one of {TRACK_KINDS}")
    arrays = storage.track_arrays(segment_ids, mode, mode if within_stored_span else None)
    if mode == GPS_TRACK:
        return {seg: Track(seg, x, y, t, no_fix=no_fix) for seg, x, y, t, no_fix in arrays}
    return {seg: Track(seg, x, y, t, frame=frame) for seg, x, y, t, frame in arrays}


def _instant(seconds: float) -> datetime:
    # Millisecond rounding removes the float noise of the database conversion.
    return datetime.fromtimestamp(round(float(seconds), 3), UTC)


@dataclass
class SegmentTrack:
    segment: Segment
    x: np.ndarray
    y: np.ndarray
    frame: str = ""

    def __len__(self) -> int:
        return len(self.x)

    def coordinates(self) -> list[list[float]]:
        """[[x, y], ...] as plain floats, ready for JSON."""
        return np.column_stack((self.x, self.y)).tolist()


def masters(*, leg=None, shift=None, test_event=None) -> QuerySet[Segment]:
    """Master segments of one leg, shift or test event, oldest first."""
    queryset = Segment.objects.masters()
    if leg is not None:
        queryset = queryset.filter(leg=leg)
    if shift is not None:
        queryset = queryset.filter(leg__shift=shift)
    if test_event is not None:
        queryset = queryset.filter(leg__shift__test_event=test_event)
    return queryset.order_by("start", "id")


def segment_tracks(
    segments: QuerySet[Segment] | list[Segment],
    mode: str = GPS_TRACK,
    loaded: dict[int, Track] | None = None,
) -> list[SegmentTrack]:
    """One track per master that has usable points, in the masters' order.

    GPS tracks hold longitude (x) and latitude (y); local tracks map-frame metres.
    """
    segments = list(segments)
    if loaded is None:
        loaded = load_tracks([s.pk for s in segments], mode)
    return [
        SegmentTrack(s, loaded[s.pk].x, loaded[s.pk].y, loaded[s.pk].frame)
        for s in segments
        if s.pk in loaded and len(loaded[s.pk])
    ]


def with_last_position(queryset: QuerySet, leg_field: str = "leg") -> QuerySet:
    """``queryset`` (rows that name a leg in ``leg_field``) annotated with
    ``last_lon``/``last_lat``: where the leg's GPS track ends now, or None.

    Subqueries, so a list of any length stays one query.  The end is the newest
    usable fix of the newest master segment that has one: by the robot's clock,
    or by arrival where no fix has a stamp.  Each is the last entry of the
    pose_segment_time index (read backwards), so the cost does not grow with
    the track: ordering by the two times merged would read every fix of it."""
    usable = Pose.objects.filter(USABLE_FIX, segment=OuterRef("pk"))
    stamped = usable.filter(robot_stamp__isnull=False).order_by("-robot_stamp", "-received", "-id")
    unstamped = usable.filter(robot_stamp__isnull=True).order_by("-received", "-id")
    newest_fix = Coalesce(Subquery(stamped.values("pk")[:1]), Subquery(unstamped.values("pk")[:1]))
    fix_of_leg = (
        Segment.objects.masters()
        .filter(leg=OuterRef(leg_field))
        .annotate(_fix=newest_fix)
        .filter(_fix__isnull=False)
        .order_by("-start", "-id")
        .values("_fix")[:1]
    )

    def coordinate(function):
        point = Pose.objects.filter(pk=OuterRef("_last_fix"))
        return Subquery(point.annotate(_v=Coordinate("point", function=function)).values("_v")[:1])

    return queryset.annotate(_last_fix=Subquery(fix_of_leg)).annotate(
        last_lon=coordinate("ST_X"), last_lat=coordinate("ST_Y")
    )
