"""Take-over hotspots: where the chosen test events' interventions started, grouped.

A take-over's position is the first point of its ITO run's measured path
(its start position, else its first pose), so it is where the operator took
over.  GPS positions are projected to metres east/north of their common
centre (azimuthal equidistant, true distances over a test site); local
positions are already metres in the map frame.

Clustering is single linkage with a distance cut: two take-overs at most
``HOTSPOT_RADIUS_M`` apart are in the same hotspot, and so is every take-over
linked to it through such pairs (scipy's hierarchical clustering).  Hotspots
are numbered 1, 2, ... by size (most take-overs first), then by their first
take-over in time, so the numbers on the map, in the PDF's table and in the
JSON agree.
"""

from collections import Counter
from dataclasses import dataclass

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage

from reports.projection import local_frame
from reports.selectors.formulas import HOTSPOT_RADIUS_M
from reports.selectors.statistics import Run
from telemetry.selectors.tracks import GPS


@dataclass
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
    if mode == GPS and len(points):
        forward, _ = local_frame(float(x.mean()), float(y.mean()))
        x, y = forward.transform(x, y)
    return np.column_stack([np.asarray(x, dtype=float), np.asarray(y, dtype=float)])


def cluster_labels(xy: np.ndarray, radius: float = HOTSPOT_RADIUS_M) -> list[int]:
    """Hotspot number (1 = most take-overs) of each point; see the module docstring."""
    if len(xy) == 0:
        return []
    if len(xy) == 1:
        return [1]
    raw = fcluster(linkage(xy, method="single"), t=radius, criterion="distance")
    sizes = Counter(raw)
    first = {}
    for index, group in enumerate(raw):
        first.setdefault(group, index)
    order = sorted(sizes, key=lambda g: (-sizes[g], first[g]))
    number = {group: i + 1 for i, group in enumerate(order)}
    return [number[g] for g in raw]


def hotspots(runs_of: dict[int, list[Run]], mode: str = GPS) -> list[dict]:
    """JSON-ready hotspots, numbered; each lists its take-overs with the segment's
    id, GUI label, test event, shift and leg (enough for a link to the segment)."""
    points = take_overs(runs_of)
    xy = metres(points, mode)
    numbers = cluster_labels(xy)
    found: dict[int, dict] = {}
    for point, (east, north), number in zip(points, xy, numbers, strict=True):
        spot = found.setdefault(
            number, {"number": number, "count": 0, "reasons": Counter(), "members": []}
        )
        spot["count"] += 1
        reasons = sorted(set(point.run.counted_reasons))
        spot["reasons"].update(reasons)
        spot["members"].append(
            {
                "test_event": point.test_event,
                "shift": point.run.shift_id,
                "leg": point.run.leg_id,
                "segment": point.run.id,
                "label": point.run.label,
                "start": point.run.start.isoformat(),
                "reasons": reasons,
                "x": point.x,
                "y": point.y,
                "east": float(east),
                "north": float(north),
            }
        )
    result = []
    for number in sorted(found):
        spot = found[number]
        members = spot["members"]
        spot["x"] = float(np.mean([m["x"] for m in members]))
        spot["y"] = float(np.mean([m["y"] for m in members]))
        spot["east"] = float(np.mean([m["east"] for m in members]))
        spot["north"] = float(np.mean([m["north"] for m in members]))
        spot["reasons"] = dict(sorted(spot["reasons"].items(), key=lambda kv: (-kv[1], kv[0])))
        result.append(spot)
    return result
