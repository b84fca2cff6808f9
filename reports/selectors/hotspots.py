"""Take-over hotspots: where the chosen test events' interventions started, grouped.

A take-over's position is the first point of its ITO run's measured path
(its start position, else its first pose), so it is where the operator took
over.  GPS positions are projected to metres east/north of their common
centre (azimuthal equidistant, true distances over a test site); local
positions are already metres in the map frame.

Clustering is single linkage with a distance cut: two take-overs at most
``HOTSPOT_RADIUS_M`` apart are in the same hotspot, and so is every take-over
linked to it through such pairs (the connected components of the pairs
within the radius, found with a KD-tree).  Hotspots are numbered 1, 2, ...
by size (most take-overs first), then by their first take-over in time, so
the numbers on the map, in the PDF's table and in the JSON agree.
"""

from collections import Counter, defaultdict
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from reports.projection import local_frame
from reports.selectors.formulas import HOTSPOT_RADIUS_M
from reports.selectors.statistics import Run
from telemetry.storage.keys import GPS_TRACK


@dataclass(slots=True)
class TakeOver:
    test_event: int
    run: Run
    x: float  # longitude (GPS) or map-frame metres (local)
    y: float


def take_overs(runs_of: dict[int, list[Run]]) -> list[TakeOver]:
    """The interventions with a known position, per test event in driving order."""
    return [
        TakeOver(event_id, run, float(run.origin[0]), float(run.origin[1]))
        for event_id, runs in runs_of.items()
        for run in runs
        if run.is_intervention and run.origin is not None
    ]


def metres(points: list[TakeOver], mode: str) -> np.ndarray:
    """N x 2 positions in metres (east, north) around the points' centre."""
    x = np.array([p.x for p in points], dtype=float)
    y = np.array([p.y for p in points], dtype=float)
    if mode == GPS_TRACK and len(points):
        forward, _ = local_frame(float(x.mean()), float(y.mean()))
        x, y = forward.transform(x, y)
    return np.column_stack([np.asarray(x, dtype=float), np.asarray(y, dtype=float)])


def cluster_labels(xy: np.ndarray, radius: float = HOTSPOT_RADIUS_M) -> list[int]:
    """Hotspot number (1 = most take-overs) of each point; see the module docstring."""
    if len(xy) == 0:
        return []
    raw = _linked_groups(xy, radius)
    sizes = Counter(raw)
    first = {}
    for index, group in enumerate(raw):
        first.setdefault(group, index)
    order = sorted(sizes, key=lambda g: (-sizes[g], first[g]))
    number = {group: i + 1 for i, group in enumerate(order)}
    return [number[g] for g in raw]


def _linked_groups(xy: np.ndarray, radius: float) -> list[int]:
    """A group id per point: single linkage cut at ``radius`` is the connected
    components of the pairs at most ``radius`` apart.  A KD-tree finds the pairs
    (with a margin; each is then measured as scipy's pdist measures it), so the
    cost grows with the pairs near each other, not with all n² of them."""
    pairs = cKDTree(xy).query_pairs(radius * (1 + 1e-9), output_type="ndarray")
    step = xy[pairs[:, 0]] - xy[pairs[:, 1]]
    pairs = pairs[np.sqrt(np.square(step).sum(axis=1)) <= radius]
    links = coo_matrix(
        (np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(len(xy),) * 2
    )
    return connected_components(links, directed=False)[1].tolist()


def hotspots(runs_of: dict[int, list[Run]], mode: str = GPS_TRACK) -> list[dict]:
    """JSON-ready hotspots, numbered; each lists its take-overs with the segment's
    id, GUI label, test event, shift and leg (enough for a link to the segment)."""
    points = take_overs(runs_of)
    xy = metres(points, mode)
    numbers = np.array(cluster_labels(xy), dtype=np.int64)
    members_of: dict[int, list[int]] = defaultdict(list)
    for index, number in enumerate(numbers.tolist()):
        members_of[number].append(index)
    # x, y as given and east, north in metres: a spot's position is their means,
    # summed per spot in one pass over each column.
    # Spots are numbered from 1: the count at 0 is kept from dividing by zero.
    counts = np.maximum(np.bincount(numbers), 1)
    columns = [np.array([p.x for p in points]), np.array([p.y for p in points]), *xy.T]
    means = [(np.bincount(numbers, weights=c) / counts).tolist() for c in columns]
    metres_of = xy.tolist()
    result = []
    for number in sorted(members_of):
        chosen = members_of[number]
        members = [_member(points[i], *metres_of[i]) for i in chosen]
        reasons = Counter(reason for m in members for reason in m["reasons"])
        x, y, east, north = (mean[number] for mean in means)
        result.append(
            {
                "number": number,
                "count": len(chosen),
                "reasons": dict(sorted(reasons.items(), key=lambda kv: (-kv[1], kv[0]))),
                "members": members,
                **{"x": x, "y": y, "east": east, "north": north},
            }
        )
    return result


def _member(point: TakeOver, east: float, north: float) -> dict:
    run = point.run
    return {
        "test_event": point.test_event,
        "shift": run.shift_id,
        "leg": run.leg_id,
        "segment": run.id,
        "label": run.label,
        "start": run.start.isoformat(),
        "reasons": sorted(set(run.counted_reasons)),
        "x": point.x,
        "y": point.y,
        "east": east,
        "north": north,
    }
