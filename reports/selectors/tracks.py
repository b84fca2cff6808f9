"""Time-ordered track points of master segments, for distances, maps and exports.

Points are ordered by the robot's clock, then by arrival, then by id, so a
late-arriving batch from the collector's offline queue still lands where it
was driven.  Fixes flagged "no fix" carry no usable position and are dropped.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
from django.db.models import F, FloatField, Func
from django.db.models.functions import Coalesce
from pyproj import Geod

from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus

GPS = "gps"
LOCAL = "local"
MODES = (GPS, LOCAL)

WGS84 = Geod(ellps="WGS84")

# Two consecutive points further apart in time than this are reported as a gap.
GAP_SECONDS = 10.0


class _Coordinate(Func):
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


def path_length(x: Iterable[float], y: Iterable[float], mode: str) -> float:
    """Length of a polyline: geodesic on the WGS84 ellipsoid (GPS) or planar (local)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(x) < 2:
        return 0.0
    if mode == GPS:
        _, _, steps = WGS84.inv(x[:-1], y[:-1], x[1:], y[1:])
        return float(np.sum(steps))
    return float(np.sum(np.hypot(np.diff(x), np.diff(y))))


class _Epoch(Func):
    """Seconds since 1970 as a float, computed in the database: converting
    200 000 timestamps to datetimes in Python would take most of the time."""

    output_field = FloatField()

    def as_sqlite(self, compiler, connection, **extra):
        # Django stores UTC text timestamps in SQLite; julianday() reads them.
        template = "((julianday(%(expressions)s) - 2440587.5) * 86400.0)"
        return self.as_sql(compiler, connection, template=template, **extra)

    def as_postgresql(self, compiler, connection, **extra):
        template = "EXTRACT(EPOCH FROM %(expressions)s)::double precision"
        return self.as_sql(compiler, connection, template=template, **extra)


def _rows(segment_ids, mode):
    order = ("segment_id", F("robot_stamp").asc(nulls_last=True), "received", "id")
    model = Pose if mode == GPS else LocalPose
    qs = model.objects.filter(segment_id__in=segment_ids).annotate(
        _t=_Epoch(Coalesce("robot_stamp", "received"))
    )
    if mode == GPS:
        qs = qs.annotate(
            _x=_Coordinate("point", function="ST_X"), _y=_Coordinate("point", function="ST_Y")
        )
        columns = ("segment_id", "_x", "_y", "_t", "fix_status")
    else:
        qs = qs.annotate(_x=F("x"), _y=F("y"))
        columns = ("segment_id", "_x", "_y", "_t", "frame")
    return qs.order_by(*order).values_list(*columns).iterator(chunk_size=20000)


def load_tracks(segment_ids: list[int], mode: str = GPS) -> dict[int, Track]:
    """Tracks of the given master segments; segments without points are absent."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}")
    buckets: dict[int, tuple[list, list, list, list]] = {}
    no_fix: dict[int, int] = {}
    for seg, x, y, t, extra in _rows(list(segment_ids), mode):
        if mode == GPS and extra == FixStatus.NO_FIX:
            no_fix[seg] = no_fix.get(seg, 0) + 1
            continue
        bucket = buckets.setdefault(seg, ([], [], [], []))
        bucket[0].append(x)
        bucket[1].append(y)
        bucket[2].append(t)
        if mode == LOCAL and not bucket[3]:
            bucket[3].append(extra)
    tracks = {}
    for seg, (xs, ys, ts, frame) in buckets.items():
        t = np.asarray(ts, dtype=float)
        tracks[seg] = Track(
            segment_id=seg,
            x=np.asarray(xs, dtype=float),
            y=np.asarray(ys, dtype=float),
            t=t,
            frame=frame[0] if frame else "",
            no_fix=no_fix.pop(seg, 0),
        )
    for seg, count in no_fix.items():
        tracks[seg] = Track(seg, np.empty(0), np.empty(0), np.empty(0), no_fix=count)
    return tracks


def _instant(seconds: float) -> datetime:
    # Millisecond rounding removes the float noise of the database conversion.
    return datetime.fromtimestamp(round(float(seconds), 3), UTC)
