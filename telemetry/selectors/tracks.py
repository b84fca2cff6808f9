"""Time-ordered track points of master segments, for distances, maps, the API and exports.

Points are ordered by the robot's clock, then by arrival, then by id, so a
late-arriving batch from the collector's offline queue still lands where it
was driven.  Fixes flagged "no fix" carry no usable position and are dropped.
"""

import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from datetime import UTC, datetime

import numpy as np
import shapely
from django.db import connection, transaction
from django.db.models import Count, F, FloatField, Func, Max, OuterRef, QuerySet, Subquery, Value
from django.db.models.functions import Coalesce

from common.sql import bound_cursor
from events.models import Segment
from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus

GPS = "gps"
LOCAL = "local"
MODES = (GPS, LOCAL)

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


# Zoom levels Leaflet offers on the GPS map; a tolerance below 1e-9 degrees
# (0.1 mm) keeps every point anyway.
MAX_ZOOM = 24


def zoom_tolerance(zoom: int) -> float:
    """Half a screen pixel at a Web Mercator zoom level, in degrees of longitude.

    A pixel spans fewer degrees of latitude (by cos(latitude)); half a pixel
    keeps the drawn error below one pixel up to about 60 degrees."""
    return 360.0 / (256 * 2**zoom) / 2


# The local map (Leaflet's CRS.Simple) shows one map-frame metre as 2**zoom pixels;
# it zooms out further than the GPS map.
MIN_LOCAL_ZOOM = -10


def local_zoom_tolerance(zoom: int) -> float:
    """Half a screen pixel at a local-map zoom level, in map-frame metres."""
    return 0.5 / 2**zoom


def tolerance(mode: str, zoom: int) -> float:
    """What a track may be thinned by at ``zoom`` of its map without a visible change."""
    return zoom_tolerance(zoom) if mode == GPS else local_zoom_tolerance(zoom)


def _mercator(latitude: np.ndarray) -> np.ndarray:
    # Web Mercator y in degrees-of-longitude units, so it compares with longitudes.
    return np.degrees(np.log(np.tan(np.pi / 4 + np.radians(latitude) / 2)))


def fit_zoom(mode: str, tracks: list[Track], width: int, height: int) -> int | None:
    """The largest whole zoom at which every point of ``tracks`` fits a map of
    ``width`` x ``height`` pixels (what the map picks when it shows the whole
    leg); None without points."""
    xs = [t.x for t in tracks if len(t)]
    if not xs:
        return None
    x = np.concatenate(xs)
    y = np.concatenate([t.y for t in tracks if len(t)])
    if mode == GPS:
        y = _mercator(y)
    # A track of one point (or a straight line) still gets a finite zoom.
    span_x = max(float(x.max() - x.min()), 1e-12)
    span_y = max(float(y.max() - y.min()), 1e-12)
    if mode == GPS:
        pixels_per_unit = min(width / span_x, height / span_y) * 360 / 256
        low = 0
    else:
        pixels_per_unit = min(width / span_x, height / span_y)
        low = MIN_LOCAL_ZOOM
    return int(min(max(np.floor(np.log2(pixels_per_unit)), low), MAX_ZOOM))


def drawn(
    x: np.ndarray,
    y: np.ndarray,
    tolerance: float,
    bbox: tuple[float, float, float, float] | None = None,
    bbox_tolerance: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The track as a map draws it: thinned by ``tolerance``, and inside ``bbox``
    (xmin, ymin, xmax, ymax: the area in view) by the finer ``bbox_tolerance``.

    The track is cut into runs inside and outside the box; neighbouring runs
    share their end point, which Douglas-Peucker keeps, so the pieces join
    without a gap.  A point just outside the box belongs to the run inside, so
    the line leaves the view at full detail."""
    if bbox is None or len(x) < 3:
        return simplified(x, y, tolerance)
    xmin, ymin, xmax, ymax = bbox
    inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
    near = inside.copy()
    near[1:] |= inside[:-1]
    near[:-1] |= inside[1:]
    cuts = np.flatnonzero(near[1:] != near[:-1]) + 1
    starts = np.concatenate([[0], cuts])
    ends = np.concatenate([cuts, [len(x)]])
    xs, ys = [], []
    for first, stop in zip(starts, ends, strict=True):
        # Each run but the last reaches into the next one's first point.
        last = min(stop + 1, len(x))
        fine = bbox_tolerance if near[first] else tolerance
        px, py = simplified(x[first:last], y[first:last], fine)
        if stop < len(x):
            px, py = px[:-1], py[:-1]
        xs.append(px)
        ys.append(py)
    return np.concatenate(xs), np.concatenate(ys)


def thinned(track: Track, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """``simplified`` of a whole track, remembered on the track: a kept track
    (``kept_tracks``) is thinned once per zoom, not once per request."""
    found = track.memo.get(tolerance)
    if found is None:
        found = track.memo[tolerance] = simplified(track.x, track.y, tolerance)
    return found


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
            _x=Coordinate("point", function="ST_X"), _y=Coordinate("point", function="ST_Y")
        )
        columns = ("segment_id", "_x", "_y", "_t", "fix_status")
    else:
        qs = qs.annotate(_x=F("x"), _y=F("y"))
        columns = ("segment_id", "_x", "_y", "_t", "frame")
    return qs.order_by(*order).values_list(*columns).iterator(chunk_size=20000)


# A point as ST_AsBinary(point, 'NDR') gives it: little-endian WKB (byte order, type, x, y).
_WKB_POINT = np.dtype([("order", "u1"), ("type", "<u4"), ("x", "<f8"), ("y", "<f8")])
# timestamptz_send: big-endian microseconds since 2000-01-01 UTC.
_PG_STAMP = np.dtype(">i8")
_PG_EPOCH_MICROSECONDS = 946_684_800_000_000
# float8send: a big-endian double.
_PG_FLOAT = np.dtype(">f8")


# The keys of the pose_segment_time and localpose_segment_time indexes.
_DRIVING_ORDER = "ORDER BY segment_id, robot_stamp ASC NULLS LAST, received, id"


def gps_tracks_sql() -> str:
    """The query of the GPS tracks on PostgreSQL (one parameter: the segment ids),
    so the benchmark can show its plan."""
    no_fix = int(FixStatus.NO_FIX)
    return (
        "SELECT segment_id, "
        f"string_agg(ST_AsBinary(point, 'NDR'), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"string_agg(timestamptz_send(t), ''::bytea) FILTER (WHERE fix_status <> {no_fix}), "
        f"count(*) FILTER (WHERE fix_status = {no_fix}) "
        "FROM (SELECT segment_id, point, fix_status, COALESCE(robot_stamp, received) AS t "
        f'FROM "{Pose._meta.db_table}" WHERE segment_id = ANY(%s::bigint[]) '
        f"{_DRIVING_ORDER}) AS ordered "
        "GROUP BY segment_id"
    )


def local_tracks_sql() -> str:
    """The query of the local tracks on PostgreSQL, read the way the GPS tracks
    are; the frame is that of each track's first point, found through the
    same index."""
    table = LocalPose._meta.db_table
    return (
        "SELECT segment_id, string_agg(float8send(x), ''::bytea), "
        "string_agg(float8send(y), ''::bytea), string_agg(timestamptz_send(t), ''::bytea), "
        f'(SELECT frame FROM "{table}" AS first WHERE first.segment_id = ordered.segment_id '
        "ORDER BY robot_stamp ASC NULLS LAST, received, id LIMIT 1) "
        "FROM (SELECT segment_id, x, y, COALESCE(robot_stamp, received) AS t "
        f'FROM "{table}" WHERE segment_id = ANY(%s::bigint[]) {_DRIVING_ORDER}) AS ordered '
        "GROUP BY segment_id"
    )


def _packed_rows(query: str, segment_ids: list[int]) -> list[tuple]:
    """Tracks read as one row per segment holding its points and times packed
    into byte strings in driving order: a million points cross the wire as
    1 000 rows that numpy reads without a Python object per point.

    The inner query walks the segment+time index, whose keys are the driving
    order and which covers the columns read here, so PostgreSQL neither sorts
    nor reads the table (an Index Only Scan once vacuum has marked the pages).
    An aggregate over a sorted subquery takes the rows in the subquery's order
    (PostgreSQL's manual, "Aggregate Expressions"; the ORDER BY keeps the
    planner from flattening the subquery); an ``ORDER BY`` inside the aggregate
    would make PostgreSQL 15 sort every segment again, a third of the query's
    time.  The time leaves as the stored timestamp, which costs nothing to
    send, where ``date_part`` would convert every row.  The result comes in
    binary, as the bytes are stored: Django's cursors bind parameters on the
    client, which returns text, and hex-decoding the 37 MB of a million points
    took about a quarter of a second.  JIT compiling is off for this statement:
    for a plain scan it took longer than the time it saved (``SET LOCAL``: until
    the end of the caller's transaction where there is one, which only costs
    other big queries in it their JIT)."""
    with transaction.atomic():
        with connection.cursor() as cursor:
            cursor.execute("SET LOCAL jit = off")
        with bound_cursor(binary_results=True) as cursor:
            cursor.execute(query, [segment_ids])
            return cursor.fetchall()


def _seconds(stamps: bytes | None) -> np.ndarray:
    # The same single rounding as PostgreSQL's epoch: exact microseconds, then float.
    micro = np.frombuffer(stamps or b"", dtype=_PG_STAMP) + _PG_EPOCH_MICROSECONDS
    return micro / 1e6


def _gps_tracks_postgis(segment_ids: list[int]) -> dict[int, Track]:
    tracks = {}
    for seg, points, stamps, no_fix_count in _packed_rows(gps_tracks_sql(), segment_ids):
        points = np.frombuffer(points or b"", dtype=_WKB_POINT)
        tracks[seg] = Track(
            segment_id=seg,
            x=points["x"].astype(float),
            y=points["y"].astype(float),
            t=_seconds(stamps),
            no_fix=no_fix_count,
        )
    return tracks


def _local_tracks_postgres(segment_ids: list[int]) -> dict[int, Track]:
    tracks = {}
    for seg, x, y, stamps, frame in _packed_rows(local_tracks_sql(), segment_ids):
        tracks[seg] = Track(
            segment_id=seg,
            x=np.frombuffer(x, dtype=_PG_FLOAT).astype(float),
            y=np.frombuffer(y, dtype=_PG_FLOAT).astype(float),
            t=_seconds(stamps),
            frame=frame or "",
        )
    return tracks


def load_tracks(segment_ids: list[int], mode: str = GPS) -> dict[int, Track]:
    """Tracks of the given master segments; segments without points are absent."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}")
    if connection.vendor == "postgresql":
        packed = _gps_tracks_postgis if mode == GPS else _local_tracks_postgres
        return packed([int(pk) for pk in segment_ids])
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


class _Kept:
    """Tracks kept between the map's reads in each web process, bounded in
    points (x, y and t: 24 bytes each), least recently read dropped first."""

    def __init__(self, points: int):
        self.points = points
        self.slots: OrderedDict[tuple[str, int], tuple[tuple, Track]] = OrderedDict()
        self.total = 0
        self.lock = threading.Lock()

    def get(self, slot: tuple[str, int], key: tuple) -> Track | None:
        with self.lock:
            kept = self.slots.get(slot)
            if kept is None or kept[0] != key:
                return None
            self.slots.move_to_end(slot)
            return kept[1]

    def put(self, slot: tuple[str, int], key: tuple, track: Track) -> None:
        with self.lock:
            old = self.slots.pop(slot, None)
            if old is not None:
                self.total -= len(old[1])
            if len(track) > self.points:
                return
            self.slots[slot] = (key, track)
            self.total += len(track)
            while self.total > self.points:
                _, (_, dropped) = self.slots.popitem(last=False)
                self.total -= len(dropped)

    def holds_any(self, segment_ids) -> bool:
        with self.lock:
            return any((mode, seg) in self.slots for mode in MODES for seg in segment_ids)

    def clear(self) -> None:
        with self.lock:
            self.slots.clear()
            self.total = 0


# About 100 MB per web process.
_kept = _Kept(4_000_000)
# Held while tracks that are not kept are read, so a request that arrives
# during a read ahead of the same leg (gui.views.gui_api.read_ahead) waits for
# it and takes its tracks instead of reading them a second time.
_reading = threading.Lock()


def pose_counts(segment_ids: list[int], modes=MODES) -> dict[tuple[str, int], tuple[int, int]]:
    """{(mode, segment id): (poses stored, newest pose id)} of the segments
    that have poses, in one query (an index-only count on PostgreSQL)."""
    parts = [
        (Pose if mode == GPS else LocalPose)
        .objects.filter(segment_id__in=segment_ids)
        .values("segment_id")
        .annotate(_n=Count("id"), _newest=Max("id"), _mode=Value(mode))
        .values_list("_mode", "segment_id", "_n", "_newest")
        .order_by()
        for mode in modes
    ]
    if not segment_ids or not parts:
        return {}
    rows = parts[0].union(*parts[1:], all=True) if len(parts) > 1 else parts[0]
    return {(mode, seg): (n, newest) for mode, seg, n, newest in rows}


def kept_tracks(segments: list[Segment], modes=MODES) -> dict[str, dict[int, Track]]:
    """``load_tracks`` of each mode for the map, which asks again at every
    visit, zoom and live update: {mode: {segment id: track}}.

    A track read before in this process is used again while its segment's
    count of poses and newest pose id are unchanged.  Poses are only ever
    added (a late batch from a collector's spool may still arrive for a closed
    segment) and deleted with their segment, and every added pose raises the
    count, so a changed track is always read again; its segment's uid tells it
    from an older segment that had the same id (a database restored under a
    running server).  Two queries at most per mode, however many segments."""
    by_id = {s.pk: s for s in segments}
    counts = pose_counts(list(by_id), modes)
    found: dict[str, dict[int, Track]] = {mode: {} for mode in modes}
    if _take_kept(found, by_id, counts):
        return found
    with _reading:
        if _take_kept(found, by_id, counts):
            return found
        for mode, tracks in found.items():
            ids = [seg for (m, seg) in counts if m == mode and seg not in tracks]
            if not ids:
                continue
            # A pose stored after the count was taken is in the track read now and
            # changes the count again, so the next read replaces this one.
            read = load_tracks(ids, mode)
            tracks.update(read)
            for seg, track in read.items():
                key = (by_id[seg].uid, *counts[mode, seg])
                # What the track was read for, so results derived from it can be kept too.
                track.memo["kept"] = (mode, *key)
                _kept.put((mode, seg), key, track)
    return found


def _take_kept(found: dict[str, dict[int, Track]], by_id: dict, counts: dict) -> bool:
    """Puts the kept tracks of ``counts`` into ``found``; True when all were kept."""
    complete = True
    for (mode, seg), count in counts.items():
        if seg in found[mode]:
            continue
        track = _kept.get((mode, seg), (by_id[seg].uid, *count))
        if track is None:
            complete = False
        else:
            found[mode][seg] = track
    return complete


def keeps_any(segments: list[Segment]) -> bool:
    """Whether this process keeps a track of any of ``segments``, current or
    not (no query: what ``kept_tracks`` would then read is what changed)."""
    return _kept.holds_any([s.pk for s in segments])


def forget_kept_tracks() -> None:
    """Empties this process's kept tracks (tests that compare a fresh read)."""
    _kept.clear()


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
        return Subquery(point.annotate(_v=Coordinate("point", function=function)).values("_v")[:1])

    return queryset.annotate(_last_fix=Subquery(fix_of_leg)).annotate(
        last_lon=coordinate("ST_X"), last_lat=coordinate("ST_Y")
    )
