"""Segment maps as vector sketches that typst draws from JSON.

A report has one small map per segment; drawn with matplotlib they would take
most of a report's time.  A sketch is
only the track, its start and a scale bar, scaled into a box in points, so
typst draws it as a few vector paths in no measurable time.  The shift's
overview map (with tiles) stays a matplotlib figure.
"""

import numpy as np

from reports.charts.maps import nice_length, scale_label
from reports.projection import local_frame
from telemetry.storage.keys import GPS_TRACK

# Enough points for a 4 cm sketch: more cannot be seen and only fill the PDF.
MAX_POINTS = 400
MIN_SPAN_M = 10.0


def _thinned(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(x) <= MAX_POINTS:
        return x, y
    keep = np.unique(np.linspace(0, len(x) - 1, MAX_POINTS).round().astype(int))
    return x[keep], y[keep]


def track_sketch(x, y, mode: str, width_pt: float, height_pt: float) -> dict | None:
    """{"w", "h", "points": [[x, y] in points, y down], "scale": {"pt", "label"}}."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if not len(x):
        return None
    centre = float((x.min() + x.max()) / 2), float((y.min() + y.max()) / 2)
    # Thinned by index first, so only the points drawn are projected.
    x, y = _thinned(x, y)
    if mode == GPS_TRACK:
        forward, _ = local_frame(*centre)
        x, y = forward.transform(x, y)
        x, y = np.asarray(x), np.asarray(y)
    span = max(float(np.ptp(x)) / width_pt, float(np.ptp(y)) / height_pt, MIN_SPAN_M / width_pt)
    # 10 % margin on each side: metres per point.
    per_pt = span / 0.8
    cx, cy = (x.min() + x.max()) / 2, (y.min() + y.max()) / 2
    px = (x - cx) / per_pt + width_pt / 2
    py = height_pt / 2 - (y - cy) / per_pt
    length = nice_length(width_pt * per_pt)
    return {
        "w": width_pt,
        "h": height_pt,
        "points": np.column_stack((px.round(2), py.round(2))).tolist(),
        "scale": {"pt": round(length / per_pt, 2), "label": scale_label(length)},
    }
