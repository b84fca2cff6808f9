"""Did the robot drive the same route: how far driven routes lie apart.

A leg's route is its GPS track in driving order (every master segment, one
after the other); a test case's planned route is its line, with a point every
metre so that its deviation is measured along it, not at its few corners.
Routes are compared in one local metric frame (reports.projection) as GEOS
lines (shapely): the deviation of each point of one route from the other line
(mean, 95th percentile, maximum, and the stretches beyond a threshold) and
their discrete Fréchet distance, which also tells a route driven backwards or
in another order from the same route.

The cost is bounded: at most MAX_ROUTES routes of at most MAX_POINTS points
each.  A longer leg is simplified (Douglas-Peucker) at the smallest tolerance
that brings it under MAX_POINTS, a longer planned route measured at a wider
spacing, and the answer names the tolerance.  The Fréchet distance is the
dynamic programme over the anti-diagonals of the coupling table (time n·m,
memory n + m): GEOS's own grows faster than n·m.
"""

from dataclasses import dataclass

import numpy as np
import shapely
from django.utils.translation import gettext as _

from events.models import Leg, TestCase
from reports.projection import local_frame
from telemetry.selectors.tracks import masters, segment_tracks
from telemetry.storage.keys import GPS_TRACK

# Metres from the other route beyond which a stretch is drawn as a deviation.
DEFAULT_THRESHOLD = 5.0
# Metres between the points a planned route is measured at.
PLANNED_SPACING = 1.0
# Points one route is compared at, and routes one request compares: two routes
# of MAX_POINTS take about a second.
MAX_POINTS = 4000
MAX_ROUTES = 6
# The first Douglas-Peucker tolerance (metres) tried on a leg above MAX_POINTS;
# doubled until it is below.
FIRST_TOLERANCE = 0.05


@dataclass(frozen=True)
class Route:
    name: str  # "leg 12" or "case 3", as the API names it
    lon: np.ndarray
    lat: np.ndarray
    title: str = ""  # what a reader calls it, for the PDF (in the language active when made)
    tolerance: float = 0.0  # metres it was simplified at to stay under MAX_POINTS

    def __len__(self) -> int:
        return len(self.lon)


def leg_route(leg: Leg) -> Route:
    tracks = segment_tracks(masters(leg=leg), GPS_TRACK)
    lon = np.concatenate([t.x for t in tracks]) if tracks else np.empty(0)
    lat = np.concatenate([t.y for t in tracks]) if tracks else np.empty(0)
    shift = leg.shift
    title = _("Test event %(event)s, shift %(shift)s, leg %(leg)s") % {
        "event": shift.test_event_id,
        "shift": shift.number,
        "leg": leg.number,
    }
    return Route(f"leg {leg.pk}", lon, lat, title)


def planned_route(case: TestCase) -> Route:
    """A test case's planned route, a point at least every PLANNED_SPACING metres."""
    lon, lat = np.asarray(case.route.coords, dtype=float).T
    to_local, from_local = local_frame(float(lon.mean()), float(lat.mean()))
    line = shapely.linestrings(np.column_stack(to_local.transform(lon, lat)))
    corners = len(lon)
    spacing = max(PLANNED_SPACING, line.length / max(MAX_POINTS - corners, 1))
    x, y = shapely.get_coordinates(shapely.segmentize(line, spacing)).T
    lon, lat = from_local.transform(x, y)
    title = _("Test case %(key)s: %(title)s (planned)") % {"key": case.key, "title": case.title}
    return Route(f"case {case.pk}", np.asarray(lon), np.asarray(lat), title)


def _bounded(route: Route, to_local, from_local) -> Route:
    """``route`` itself, or simplified at the smallest tolerance (doubling) that
    leaves at most MAX_POINTS points (a planned route only with that many corners)."""
    if len(route) <= MAX_POINTS:
        return route
    line = shapely.linestrings(np.column_stack(to_local.transform(route.lon, route.lat)))
    tolerance = FIRST_TOLERANCE
    while len(simple := shapely.get_coordinates(shapely.simplify(line, tolerance))) > MAX_POINTS:
        tolerance *= 2
    lon, lat = from_local.transform(*simple.T)
    return Route(route.name, np.asarray(lon), np.asarray(lat), route.title, tolerance)


class RouteChoiceError(ValueError):
    """The routes asked for cannot be compared; ``field`` is the parameter at fault."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


def check_threshold(metres: float) -> float:
    """The deviation threshold in metres (above 0, below a thousand kilometres), or
    RouteChoiceError on ``threshold``; the API's query and a PDF's option both."""
    if not 0 < metres < 1e6:  # also refuses nan
        raise RouteChoiceError("threshold", _("Give the threshold in metres, above 0."))
    return float(metres)


def check_route_choice(leg_ids: list[int], case_ids: list[int]) -> None:
    """Refuse (RouteChoiceError) fewer than two routes, an unknown leg or test case,
    and a test case without a planned route."""
    if len(leg_ids) + len(case_ids) < 2:
        raise RouteChoiceError(
            "leg", _("Give at least two routes: leg ids, or a leg and a test case (case=).")
        )
    if len(leg_ids) + len(case_ids) > MAX_ROUTES:
        message = _("Compare at most %(count)s routes at once.") % {"count": MAX_ROUTES}
        raise RouteChoiceError("leg", message)
    legs = set(Leg.objects.filter(pk__in=leg_ids).values_list("pk", flat=True))
    cases = dict(TestCase.objects.filter(pk__in=case_ids).values_list("pk", "route"))
    for field, ids, found, message in (
        ("leg", leg_ids, legs, _("No leg with id %(id)s.")),
        ("case", case_ids, cases, _("No test case with id %(id)s.")),
    ):
        missing = [i for i in ids if i not in found]
        if missing:
            raise RouteChoiceError(field, message % {"id": missing[0]})
    unplanned = [i for i in case_ids if cases[i] is None]
    if unplanned:
        message = _("Test case %(id)s has no planned route.") % {"id": unplanned[0]}
        raise RouteChoiceError("case", message)


def chosen_routes(leg_ids: list[int], case_ids: list[int]) -> list[Route]:
    """The legs' routes, then the test cases' planned routes, in the order given."""
    check_route_choice(leg_ids, case_ids)
    legs = Leg.objects.select_related("shift").in_bulk(leg_ids)
    cases = TestCase.objects.in_bulk(case_ids)
    return [leg_route(legs[i]) for i in leg_ids] + [planned_route(cases[i]) for i in case_ids]


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
        raise ValueError(_("%(route)s has fewer than two GPS points.") % {"route": short[0]})
    lon0 = float(np.median(np.concatenate([r.lon for r in routes])))
    lat0 = float(np.median(np.concatenate([r.lat for r in routes])))
    to_local, from_local = local_frame(lon0, lat0)
    routes = [_bounded(r, to_local, from_local) for r in routes]
    local = {r.name: np.column_stack(to_local.transform(r.lon, r.lat)) for r in routes}
    lines = {name: shapely.linestrings(xy) for name, xy in local.items()}
    pairs = []
    for i, a in enumerate(routes):
        for b in routes[i + 1 :]:
            pairs.append(
                {
                    "routes": [a.name, b.name],
                    "frechet": discrete_frechet(local[a.name], local[b.name]),
                    "deviation": {
                        a.name: deviation(a, lines[b.name], threshold, to_local),
                        b.name: deviation(b, lines[a.name], threshold, to_local),
                    },
                }
            )
    return {
        "threshold": threshold,
        "routes": {r.name: np.column_stack((r.lon, r.lat)).tolist() for r in routes},
        "simplified": {r.name: r.tolerance for r in routes if r.tolerance},
        "pairs": pairs,
    }


def discrete_frechet(a: np.ndarray, b: np.ndarray) -> float:
    """The discrete Fréchet distance of two point sequences (n×2 arrays, metres).

    The coupling table c[i, j] = max(|a_i - b_j|, min(c[i-1, j], c[i, j-1],
    c[i-1, j-1])) is filled one anti-diagonal (i + j = k) at a time, each as one
    vector step along the shorter sequence; slot 0 of a diagonal is the table's
    border (infinite)."""
    if len(a) < len(b):
        a, b = b, a
    n, m = len(a), len(b)
    before, last, diagonal = (np.full(m + 1, np.inf) for _ in range(3))
    for k in range(n + m - 1):
        j0, j1 = max(0, k - n + 1), min(m - 1, k) + 1
        i = k - np.arange(j0, j1)
        apart = np.hypot(a[i, 0] - b[j0:j1, 0], a[i, 1] - b[j0:j1, 1])
        if k == 0:
            diagonal[1] = apart[0]
        else:
            best = np.minimum(last[j0 + 1 : j1 + 1], last[j0:j1])
            np.minimum(best, before[j0:j1], out=best)
            diagonal[j0 + 1 : j1 + 1] = np.maximum(apart, best)
        if j0 > 0:
            diagonal[j0] = np.inf
        before, last, diagonal = last, diagonal, before
    return float(last[m])


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
