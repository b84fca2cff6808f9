"""The distance of a master segment: the one rule every figure uses.

The measured polyline is [start position] + the segment's poses in time order
+ [start position of the next master in the same leg].  GPS: geodesic on the
WGS84 ellipsoid; local: planar in map metres.  The joins make the distances
of consecutive segments add up to the distance driven, with no metre lost at
a mode switch.  A segment without poses still gets the straight join from its
start to the next start when both are known.

Speed: a GPS step shorter than ``SHORT_STEP`` is measured with the
ellipsoid's radii of curvature at its mid-latitude (meridian M, prime
vertical N: ds = hypot(M dphi, N cos(phi) dlambda)), in numpy; longer steps and
steps near a pole go to pyproj's geodesic.  For steps up to 100 m the two
differ by less than 0.2 micrometres up to 85 degrees latitude, and on the
equator the formula is exactly a * dlambda.

The GUI's segment list, the API, the statistics, the report and the exports
all read distances from here: from the figures stored at write time
(``stored_distances``, telemetry.services.segment_figures) or, where the
track is drawn anyway, from its poses (``measured_paths``).
"""

from collections.abc import Iterable
from dataclasses import dataclass, field
from datetime import datetime

import numpy as np
from pyproj import Geod

from events.models import Segment
from telemetry.models import SegmentFigures
from telemetry.selectors.tracks import Coordinate, Track, load_tracks
from telemetry.storage import plain_rows
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

WGS84 = Geod(ellps="WGS84")
_A = WGS84.a
_E2 = WGS84.es
# Metres: shorter GPS steps are measured with the local radii of curvature.
SHORT_STEP = 100.0
# Degrees of latitude beyond which every step goes to the geodesic.
POLAR = 85.0


def path_length(x: Iterable[float], y: Iterable[float], mode: str) -> float:
    """Length of a polyline: geodesic on the WGS84 ellipsoid (GPS) or planar (local)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(x) < 2:
        return 0.0
    return float(np.sum(_steps(x, y, mode)))


def _steps(x: np.ndarray, y: np.ndarray, mode: str, inside: np.ndarray | None = None) -> np.ndarray:
    """Length of each step x[i] -> x[i + 1].  Where ``inside`` is given, only the
    steps it marks are measured exactly: the others join two polylines laid end
    to end, and the caller ignores them."""
    if mode != GPS_TRACK:
        return np.hypot(np.diff(x), np.diff(y))
    steps = _short_steps(x, y)
    far = (steps > SHORT_STEP) | (np.abs(y[:-1]) > POLAR) | (np.abs(y[1:]) > POLAR)
    if inside is not None:
        far &= inside
    if far.any():
        where = np.flatnonzero(far)
        _, _, exact = WGS84.inv(x[where], y[where], x[where + 1], y[where + 1])
        steps[where] = exact
    return steps


def _path_lengths(x: np.ndarray, y: np.ndarray, sizes: np.ndarray, mode: str) -> list[float | None]:
    """``path_length`` of many polylines at once, given laid end to end (``sizes``
    points each), so numpy measures a million steps in a few calls instead of a
    few calls per segment.  None for a polyline of fewer than two points."""
    ends = np.cumsum(sizes)
    if len(x) < 2:
        return [None] * len(sizes)
    inside = np.ones(len(x) - 1, dtype=bool)
    # The step from a polyline's last point to the next one's first is no step.
    inside[ends[(sizes > 0) & (ends < len(x))] - 1] = False
    steps = _steps(x, y, mode, inside)
    # A polyline of two points (a join: a campaign has 60 000) is its one step,
    # taken as it is rather than summed on its own.
    last_steps = steps[np.maximum(ends - 2, 0)].tolist()
    lengths: list[float | None] = []
    for i, (size, end) in enumerate(zip(sizes.tolist(), ends.tolist(), strict=True)):
        if size < 2:
            lengths.append(None)
        elif size == 2:
            lengths.append(last_steps[i])
        else:
            lengths.append(float(np.sum(steps[end - size : end - 1])))
    return lengths


def _short_steps(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    """hypot(M dphi, N cos(phi) dlambda) at each step's mid-latitude, written with
    a third fewer passes over the arrays (a million steps per statistics):
    cos from the sine already at hand, M and N through their common factor
    a / sqrt(w), arrays reused in place."""
    sin2 = np.sin(np.radians(lat[:-1] + lat[1:]) * 0.5)
    sin2 *= sin2
    w = 1.0 - _E2 * sin2
    cos_phi = np.sqrt(1.0 - sin2, out=sin2)
    d_lambda = np.diff(lon)
    # Across the antimeridian; exact for every step shorter than 180 degrees,
    # where (d + 180) % 360 - 180 would round d to the precision of 180.
    d_lambda -= 360.0 * np.round(d_lambda / 360.0)
    np.radians(d_lambda, out=d_lambda)
    d_lambda *= cos_phi
    d_phi = np.radians(np.diff(lat))
    d_phi *= 1.0 - _E2
    d_phi /= w
    steps = np.hypot(d_phi, d_lambda)
    steps *= _A
    steps /= np.sqrt(w, out=w)
    return steps


@dataclass
class MeasuredPath:
    """The polyline a master segment's distance was measured on."""

    segment_id: int
    distance: float | None
    track: Track | None
    has_start_position: bool
    x: np.ndarray = field(default_factory=lambda: np.empty(0))
    y: np.ndarray = field(default_factory=lambda: np.empty(0))


def start_points(masters: list[Segment], mode: str) -> dict[int, tuple[float, float]]:
    """{segment id: start position} of those that have one.  Where a caller
    deferred ``start_position`` or passed rows rather than segments (the
    statistics do, for thousands of segments) the GPS positions are read as
    plain floats in one query instead of one geometry object per segment."""
    if mode != GPS_TRACK:
        return {
            m.pk: (m.start_local_x, m.start_local_y)
            for m in masters
            if m.start_local_x is not None and m.start_local_y is not None
        }
    deferred = {
        m.pk
        for m in masters
        if not isinstance(m, Segment) or "start_position" in m.get_deferred_fields()
    }
    found = {
        m.pk: (m.start_position.x, m.start_position.y)
        for m in masters
        if m.pk not in deferred and m.start_position is not None
    }
    if deferred:
        # By leg, not by id: a statistics run names a few legs instead of many
        # ids, whose quoting would take longer than the query.
        rows = (
            Segment.objects.filter(
                leg__in={m.leg_id for m in masters if m.pk in deferred},
                start_position__isnull=False,
            )
            .annotate(
                _x=Coordinate("start_position", function="ST_X"),
                _y=Coordinate("start_position", function="ST_Y"),
            )
            .values_list("pk", "_x", "_y")
        )
        found.update((pk, (x, y)) for pk, x, y in rows if pk in deferred)
    return found


def _neighbours(
    masters: Iterable[Segment], mode: str
) -> list[tuple[Segment, tuple | None, tuple | None]]:
    """(master, its start position, the next master's start position) in driving
    order; the next master is looked up among the given ones of the same leg."""
    masters = sorted(masters, key=lambda m: (m.leg_id, m.start, m.pk))
    starts = start_points(masters, mode)
    found = []
    for i, master in enumerate(masters):
        follower = masters[i + 1] if i + 1 < len(masters) else None
        if follower is not None and follower.leg_id != master.leg_id:
            follower = None
        after = starts.get(follower.pk) if follower is not None else None
        found.append((master, starts.get(master.pk), after))
    return found


def measured_paths(
    masters: Iterable[Segment], mode: str = GPS_TRACK, tracks: dict[int, Track] | None = None
) -> dict[int, MeasuredPath]:
    """Paths of the given master segments, keyed by id, measured on their poses
    (for drawing them; ``stored_distances`` gives the distances without reading poses).

    The next master of each is looked up among the given ones of the same
    leg, so pass whole legs.  ``distance`` is None when fewer than two points
    are known: nothing was measured, which is not the same as standing still.
    """
    neighbours = _neighbours(masters, mode)
    if tracks is None:
        tracks = load_tracks([m.pk for m, _, _ in neighbours], mode)
    parts = [(master, tracks.get(master.pk), start, after) for master, start, after in neighbours]
    sizes = np.array(
        [
            (start is not None) + (len(track) if track is not None else 0) + (after is not None)
            for _, track, start, after in parts
        ],
        dtype=np.int64,
    )
    # Every polyline is written once into one pair of arrays; each path keeps a view.
    x = np.empty(int(sizes.sum()))
    y = np.empty(len(x))
    paths = {}
    end = 0
    for (master, track, start, after), size in zip(parts, sizes.tolist(), strict=True):
        begin, end = end, end + size
        _fill(x[begin:end], y[begin:end], start, track, after)
        paths[master.pk] = MeasuredPath(
            segment_id=master.pk,
            distance=None,
            track=track,
            has_start_position=start is not None,
            x=x[begin:end],
            y=y[begin:end],
        )
    for path, distance in zip(paths.values(), _path_lengths(x, y, sizes, mode), strict=True):
        path.distance = distance
    return paths


def _fill(x: np.ndarray, y: np.ndarray, start, track: Track | None, after) -> None:
    """[start] + the track + [after] into ``x``/``y``, which have room for them."""
    first = 0 if start is None else 1
    if start is not None:
        x[0], y[0] = start
    if after is not None:
        x[-1], y[-1] = after
    if track is not None and len(track):
        x[first : first + len(track)] = track.x
        y[first : first + len(track)] = track.y


@dataclass(slots=True)
class StoredPath:
    """A master's path as the figures stored at write time describe it."""

    distance: float | None
    points: int = 0
    has_start_position: bool = False
    # The path's first point: the start position, else the first pose, else the next start.
    origin: tuple[float, float] | None = None
    last_stamp: datetime | None = None


def stored_paths(masters: Iterable[Segment], mode: str = GPS_TRACK) -> dict[int, StoredPath]:
    """The distance rule on the figures stored at write time (SegmentFigures): the
    join from the start position to the first point, the stored length of the
    track, the join from its last point to the next start.  No pose is read, so
    the time does not depend on how many are stored.  Pass whole legs, as for
    ``measured_paths``; distance None where fewer than two points are known."""
    neighbours = _neighbours(masters, mode)
    # By leg, not by id (quoting a campaign's ids would take longer than the
    # query); plain rows of the columns used, not model instances.
    figures = SegmentFigures.objects.filter(
        segment__leg__in={m.leg_id for m, _, _ in neighbours}, mode=mode, points__gt=0
    ).values_list(
        "segment_id", "points", "length", "first_x", "first_y", "last_x", "last_y", "last_stamp"
    )
    kept = {row[0]: row[1:] for row in plain_rows(figures)}
    joins: list[tuple[int, tuple, tuple]] = []
    paths: dict[int, StoredPath] = {}
    for master, start, after in neighbours:
        found = kept.get(master.pk)
        if found is None:
            paths[master.pk] = StoredPath(None, 0, start is not None, start or after)
            if start is not None and after is not None:
                joins.append((master.pk, start, after))
            continue
        points, length, first_x, first_y, last_x, last_y, last_stamp = found
        first = (first_x, first_y)
        known = points + (start is not None) + (after is not None)
        paths[master.pk] = StoredPath(
            length if known >= 2 else None, points, start is not None, start or first, last_stamp
        )
        if start is not None:
            joins.append((master.pk, start, first))
        if after is not None:
            joins.append((master.pk, (last_x, last_y), after))
    if joins:
        x = np.array([c for _, a, b in joins for c in (a[0], b[0])], dtype=float)
        y = np.array([c for _, a, b in joins for c in (a[1], b[1])], dtype=float)
        lengths = _path_lengths(x, y, np.full(len(joins), 2, dtype=np.int64), mode)
        for (pk, _, _), length in zip(joins, lengths, strict=True):
            paths[pk].distance = (paths[pk].distance or 0.0) + length
    return paths


def stored_distances(masters: Iterable[Segment], mode: str = GPS_TRACK) -> dict[int, float | None]:
    """{master id: distance} by ``stored_paths``."""
    return {pk: path.distance for pk, path in stored_paths(masters, mode).items()}


def displayed_distances(masters: list[Segment]) -> dict[int, float | None]:
    """What a list shows for one leg's masters: the GPS distance where one was
    measured, else the local one, else None (nothing measured)."""
    by_gps = stored_distances(masters, GPS_TRACK)
    by_local = stored_distances(masters, LOCAL_TRACK)
    return {pk: d if d is not None else by_local[pk] for pk, d in by_gps.items()}
