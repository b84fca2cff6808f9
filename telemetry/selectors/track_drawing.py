"""Tracks as the maps draw them: thinned to half a screen pixel at a zoom level,
finer inside the area in view, and the zoom at which a leg fits a map."""

import numpy as np
import shapely

from telemetry.selectors.tracks import Track
from telemetry.storage.keys import GPS_TRACK

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
    return zoom_tolerance(zoom) if mode == GPS_TRACK else local_zoom_tolerance(zoom)


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
    if mode == GPS_TRACK:
        y = _mercator(y)
    # A track of one point (or a straight line) still gets a finite zoom.
    span_x = max(float(x.max() - x.min()), 1e-12)
    span_y = max(float(y.max() - y.min()), 1e-12)
    if mode == GPS_TRACK:
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
    """``simplified`` of a whole track, remembered on the track: a cached track
    (``cached_tracks.cached_tracks``) is thinned once per zoom, not once per request."""
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
    # Without topology preservation GEOS runs plain Douglas-Peucker, much faster;
    # a drawn track may cross itself anyway.
    kept = shapely.get_coordinates(shapely.simplify(line, tolerance, preserve_topology=False))
    return kept[:, 0], kept[:, 1]
