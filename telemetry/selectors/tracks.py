"""Time-ordered track points of master segments, for distances, maps, the API and exports.

Points are ordered by the robot's clock, then by arrival, then by id, so a
late-arriving batch from the collector's offline queue still lands where it
was driven.  Fixes flagged "no fix" carry no usable position and are dropped.
"""

from collections.abc import Iterable
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
import shapely
from django.db import connection
from django.db.models import F, FloatField, Func, OuterRef, QuerySet, Subquery
from django.db.models.functions import Coalesce
from pyproj import Geod

from events.models import Segment
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


# Zoom levels Leaflet offers on the GPS map; a tolerance below 1e-9 degrees
# (0.1 mm) keeps every point anyway.
MAX_ZOOM = 24


def zoom_tolerance(zoom: int) -> float:
    """Half a screen pixel at a Web Mercator zoom level, in degrees of longitude.

    A pixel spans fewer degrees of latitude (by cos(latitude)); half a pixel
    keeps the drawn error below one pixel up to about 60 degrees."""
    return 360.0 / (256 * 2**zoom) / 2


def simplified(x: np.ndarray, y: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """The polyline with fewer points, none further than ``tolerance`` from the original
    (Douglas-Peucker, GEOS via shapely); the first and last points are kept.

    For drawing only: distances are measured on the full track."""
    if len(x) < 3 or tolerance <= 0:
        return x, y
    line = shapely.linestrings(np.column_stack([x, y]))
    # Without topology preservation GEOS runs plain Douglas-Peucker, ten times faster;
    # a drawn track may cross itself anyway.
    kept = shapely.get_coordinates(shapely.simplify(line, tolerance, preserve_topology=False))
    return kept[:, 0], kept[:, 1]


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


# One row of PostgreSQL's binary COPY for the query in _copy_columns: a field
# count, then each field as its byte length and its big-endian value.  No
# column can be NULL there, so every row has the same size.
_COPY_ROW = np.dtype(
    [
        ("fields", ">i2"),
        ("n0", ">i4"),
        ("segment", ">i8"),
        ("n1", ">i4"),
        ("x", ">f8"),
        ("n2", ">i4"),
        ("y", ">f8"),
        ("n3", ">i4"),
        ("t", ">f8"),
        ("n4", ">i4"),
        ("fix", ">i4"),
    ]
)
_COPY_HEADER = 11 + 4  # signature and flags; then the header extension's length


def _copy_columns(segment_ids: list[int]) -> np.ndarray:
    """GPS points as one structured array, read by binary COPY: a million
    points arrive in a fraction of a second instead of as a million tuples."""
    table = Pose._meta.db_table
    query = (
        "COPY (SELECT segment_id::int8, ST_X(point)::float8, ST_Y(point)::float8, "
        "EXTRACT(EPOCH FROM COALESCE(robot_stamp, received))::float8, fix_status::int4 "
        f'FROM "{table}" WHERE segment_id = ANY(%s) '
        "ORDER BY segment_id, robot_stamp ASC NULLS LAST, received, id) "
        "TO STDOUT (FORMAT BINARY)"
    )
    connection.ensure_connection()
    buffer = bytearray()
    with connection.connection.cursor() as cursor, cursor.copy(query, (segment_ids,)) as copy:
        for chunk in copy:
            buffer += chunk
    extension = int.from_bytes(buffer[_COPY_HEADER : _COPY_HEADER + 4], "big")
    start = _COPY_HEADER + 4 + extension
    count = (len(buffer) - start - 2) // _COPY_ROW.itemsize  # 2: the trailer
    return np.frombuffer(buffer, dtype=_COPY_ROW, count=count, offset=start)


def _gps_tracks_postgis(segment_ids: list[int]) -> dict[int, Track]:
    rows = _copy_columns(segment_ids)
    tracks = {}
    if not len(rows):
        return tracks
    segments = rows["segment"].astype(np.int64)
    firsts = np.flatnonzero(np.r_[True, segments[1:] != segments[:-1]])
    for begin, end in zip(firsts, np.r_[firsts[1:], len(rows)], strict=True):
        part = rows[begin:end]
        usable = part["fix"] != FixStatus.NO_FIX
        seg = int(segments[begin])
        tracks[seg] = Track(
            segment_id=seg,
            x=part["x"][usable].astype(float),
            y=part["y"][usable].astype(float),
            t=part["t"][usable].astype(float),
            no_fix=int(len(part) - usable.sum()),
        )
    return tracks


def load_tracks(segment_ids: list[int], mode: str = GPS) -> dict[int, Track]:
    """Tracks of the given master segments; segments without points are absent."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}")
    if mode == GPS and connection.vendor == "postgresql":
        return _gps_tracks_postgis([int(pk) for pk in segment_ids])
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
    queryset = Segment.objects.filter(parent__isnull=True)
    if leg is not None:
        queryset = queryset.filter(leg=leg)
    if shift is not None:
        queryset = queryset.filter(leg__shift=shift)
    if test_event is not None:
        queryset = queryset.filter(leg__shift__test_event=test_event)
    return queryset.order_by("start", "id")


def segment_tracks(
    segments: QuerySet[Segment] | list[Segment],
    mode: str = GPS,
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
    usable fix (by the robot's clock, else by arrival) of the newest master
    segment that has one."""
    newest_fix = (
        Pose.objects.filter(segment=OuterRef("pk"))
        .exclude(fix_status=FixStatus.NO_FIX)
        .order_by(Coalesce("robot_stamp", "received").desc(), "-id")
        .values("pk")[:1]
    )
    fix_of_leg = (
        Segment.objects.filter(leg=OuterRef(leg_field), parent__isnull=True)
        .annotate(_fix=Subquery(newest_fix))
        .filter(_fix__isnull=False)
        .order_by("-start", "-id")
        .values("_fix")[:1]
    )

    def coordinate(function):
        point = Pose.objects.filter(pk=OuterRef("_last_fix"))
        return Subquery(point.annotate(_v=_Coordinate("point", function=function)).values("_v")[:1])

    return queryset.annotate(_last_fix=Subquery(fix_of_leg)).annotate(
        last_lon=coordinate("ST_X"), last_lat=coordinate("ST_Y")
    )
