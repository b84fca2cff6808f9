"""Decides which positions are worth a row.

A position is kept when the robot has moved (or turned) enough since the last
kept one *and* enough time has passed, so a parked robot adds nothing and a
fast GPS does not add a row per message, while the path keeps its shape.
"""

import math

EARTH_RADIUS = 6_371_008.8


def ground_distance(lon1: float, lat1: float, lon2: float, lat2: float) -> float:
    """Metres between two WGS84 points (haversine; plenty for metre-scale steps)."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dp, dl = p2 - p1, math.radians(lon2 - lon1)
    h = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * EARTH_RADIUS * math.asin(min(1.0, math.sqrt(h)))


def angle_difference(a: float, b: float) -> float:
    return abs(math.remainder(a - b, math.tau))


class Thinner:
    """``offer(x, y, t, yaw)`` says whether to keep the sample.  With ``geographic``
    x/y are longitude/latitude in degrees, otherwise metres."""

    def __init__(self, min_distance=0.5, min_period=0.2, min_yaw=None, geographic=False):
        self.min_distance = min_distance
        self.min_period = min_period
        self.min_yaw = min_yaw
        self.geographic = geographic
        self.last: tuple[float, float, float, float | None] | None = None

    def reset(self) -> None:
        self.last = None

    def distance(self, x1, y1, x2, y2) -> float:
        if self.geographic:
            return ground_distance(x1, y1, x2, y2)
        return math.hypot(x2 - x1, y2 - y1)

    def offer(self, x: float, y: float, t: float, yaw: float | None = None) -> bool:
        if self.last is None:
            self.keep(x, y, t, yaw)
            return True
        lx, ly, lt, lyaw = self.last
        if t - lt < self.min_period:
            return False
        moved = self.distance(lx, ly, x, y) >= self.min_distance
        turned = (
            self.min_yaw is not None
            and yaw is not None
            and lyaw is not None
            and angle_difference(yaw, lyaw) >= self.min_yaw
        )
        if moved or turned:
            self.keep(x, y, t, yaw)
            return True
        return False

    def keep(self, x: float, y: float, t: float, yaw: float | None = None) -> None:
        self.last = (x, y, t, yaw)
