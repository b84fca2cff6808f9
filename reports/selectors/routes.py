"""Did the robot drive the same route: how far driven routes lie apart.

A leg's route is its GPS track in driving order (every master segment, one
after the other).  Two routes are compared in one local metric frame
(reports.projection) as GEOS lines (shapely): the deviation of each point of
one route from the other line (mean, 95th percentile, maximum, and the
stretches beyond a threshold) and their discrete Fréchet distance, which also
tells a route driven backwards or in another order from the same route.
"""

from dataclasses import dataclass

import numpy as np
import shapely

from events.models import Leg
from reports.projection import local_frame
from telemetry.selectors.tracks import GPS, masters, segment_tracks

# Metres from the other route beyond which a stretch is drawn as a deviation.
DEFAULT_THRESHOLD = 5.0


@dataclass(frozen=True)
class Route:
    name: str
    lon: np.ndarray
    lat: np.ndarray

    def __len__(self) -> int:
        return len(self.lon)


def leg_route(leg: Leg) -> Route:
    tracks = segment_tracks(masters(leg=leg), GPS)
    lon = np.concatenate([t.x for t in tracks]) if tracks else np.empty(0)
    lat = np.concatenate([t.y for t in tracks]) if tracks else np.empty(0)
    return Route(f"leg {leg.pk}", lon, lat)


def deviation(route: Route, other, threshold: float, to_local) -> dict:
    """How far the points of ``route`` lie from the line ``other`` (metres)."""
    x, y = to_local.transform(route.lon, route.lat)
    points = shapely.points(np.column_stack((x, y)))
    distances = shapely.distance(points, other)
    beyond = distances > threshold
    return {
        "mean": float(distances.mean()),
        "p95": float(np.percentile(distances, 95)),
        "max": float(distances.max()),
        "share_beyond": float(beyond.mean()),
        "beyond": _stretches(route, beyond),
    }


def compare_routes(routes: list[Route], threshold: float = DEFAULT_THRESHOLD) -> dict:
    """Each route's points and, per pair, the deviation both ways and the
    discrete Fréchet distance.  Routes need two points or more."""
    short = [r.name for r in routes if len(r) < 2]
    if short:
        raise ValueError(f"{short[0]} has fewer than two GPS points.")
    lon0 = float(np.median(np.concatenate([r.lon for r in routes])))
    lat0 = float(np.median(np.concatenate([r.lat for r in routes])))
    to_local, _ = local_frame(lon0, lat0)
    lines = {
        r.name: shapely.linestrings(np.column_stack(to_local.transform(r.lon, r.lat)))
        for r in routes
    }
    pairs = []
    for i, a in enumerate(routes):
        for b in routes[i + 1 :]:
            pairs.append(
                {
                    "routes": [a.name, b.name],
                    "frechet": float(shapely.frechet_distance(lines[a.name], lines[b.name])),
                    "deviation": {
                        a.name: deviation(a, lines[b.name], threshold, to_local),
                        b.name: deviation(b, lines[a.name], threshold, to_local),
                    },
                }
            )
    return {
        "threshold": threshold,
        "routes": {r.name: np.column_stack((r.lon, r.lat)).tolist() for r in routes},
        "pairs": pairs,
    }


def _stretches(route: Route, beyond: np.ndarray) -> list[list[list[float]]]:
    """Runs of consecutive points beyond the threshold, as [[lon, lat], ...] lines."""
    runs, start = [], None
    for i, out in enumerate([*beyond.tolist(), False]):
        if out and start is None:
            start = i
        elif not out and start is not None:
            runs.append([[float(route.lon[j]), float(route.lat[j])] for j in range(start, i)])
            start = None
    return runs
