"""Placing the local (map-frame) picture on the GPS map.

Segments that started with both a GPS fix and a local position tie the two
frames together.  From all of them we estimate the similarity transform
(scale, rotation, shift) that maps local metres onto east/north metres around
their centroid, by least squares (Umeyama's method).  The original tool used
only the first two segments and assumed scale 1, so one bad fix skewed the
whole overlay.
"""

import math
from dataclasses import dataclass

import numpy as np
from django.utils.translation import gettext
from pyproj import Geod

from events.models import Segment, Shift
from telemetry.models import MapImage

WGS84 = Geod(ellps="WGS84")


@dataclass
class Similarity:
    """local (x, y) -> east/north metres around (lon0, lat0): east_north = s R p + t."""

    lon0: float
    lat0: float
    scale: float
    rotation: float  # radians, counter-clockwise from local x to east
    tx: float
    ty: float
    pairs: int
    rms: float  # metres, residual of the fitted pairs

    def to_lon_lat(self, x: float, y: float) -> tuple[float, float]:
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        east = self.scale * (c * x - s * y) + self.tx
        north = self.scale * (s * x + c * y) + self.ty
        azimuth = math.degrees(math.atan2(east, north))
        lon, lat, _ = WGS84.fwd(self.lon0, self.lat0, azimuth, math.hypot(east, north))
        return lon, lat


def tie_points(shift: Shift) -> list[tuple[float, float, float, float]]:
    """(lon, lat, x, y) of every master segment of the shift that has both starts."""
    rows = (
        Segment.objects.masters()
        .filter(
            leg__shift=shift,
            start_position__isnull=False,
            start_local_x__isnull=False,
        )
        .order_by("start", "id")
    )
    return [
        (s.start_position.x, s.start_position.y, s.start_local_x, s.start_local_y) for s in rows
    ]


def _east_north(lon0, lat0, lons, lats) -> np.ndarray:
    azimuth, _, distance = WGS84.inv(np.full(len(lons), lon0), np.full(len(lats), lat0), lons, lats)
    azimuth = np.radians(azimuth)
    return np.column_stack([distance * np.sin(azimuth), distance * np.cos(azimuth)])


def estimate(points: list[tuple[float, float, float, float]]) -> Similarity | None:
    """Least-squares similarity from (lon, lat, x, y) pairs; None when under-determined."""
    if len(points) < 2:
        return None
    data = np.asarray(points, dtype=float)
    lon0, lat0 = float(data[:, 0].mean()), float(data[:, 1].mean())
    dst = _east_north(lon0, lat0, data[:, 0], data[:, 1])
    src = data[:, 2:4]
    src_mean, dst_mean = src.mean(axis=0), dst.mean(axis=0)
    src_c, dst_c = src - src_mean, dst - dst_mean
    variance = float((src_c**2).sum()) / len(src)
    if variance < 1e-9:
        return None  # all local starts in one spot: rotation is undefined
    # Cross-covariance as a complex number: its angle is the rotation and its
    # length over the source variance is the scale (2-D Umeyama).
    a = src_c[:, 0] + 1j * src_c[:, 1]
    b = dst_c[:, 0] + 1j * dst_c[:, 1]
    cross = complex(np.sum(np.conj(a) * b)) / len(src)
    if abs(cross) < 1e-12:
        return None
    rotation = math.atan2(cross.imag, cross.real)
    scale = abs(cross) / variance
    rot = scale * np.exp(1j * rotation)
    t = complex(*dst_mean) - rot * complex(*src_mean)
    fitted = rot * (src[:, 0] + 1j * src[:, 1]) + t
    rms = float(np.sqrt(np.mean(np.abs(fitted - (dst[:, 0] + 1j * dst[:, 1])) ** 2)))
    return Similarity(lon0, lat0, scale, rotation, t.real, t.imag, len(src), rms)


def map_corners(map_image: MapImage) -> dict[str, tuple[float, float]]:
    """Local-frame positions of the image's top-left, top-right and bottom-left corners.

    The image's bottom row is the grid's first row (ROS convention), so the
    grid origin is the bottom-left corner and the yaw turns the grid about it.
    """
    c, s = math.cos(map_image.origin_yaw), math.sin(map_image.origin_yaw)
    w = map_image.width * map_image.resolution
    h = map_image.height * map_image.resolution

    def place(u, v):
        return (map_image.origin_x + c * u - s * v, map_image.origin_y + s * u + c * v)

    return {"top_left": place(0, h), "top_right": place(w, h), "bottom_left": place(0, 0)}


def overlay(shift: Shift, map_image: MapImage | None) -> dict:
    """What the GUI needs to draw the local map on the GPS map (JSON-ready)."""
    fit = estimate(tie_points(shift))
    if fit is None:
        return {
            "available": False,
            "detail": gettext(
                "Needs at least two segments that started with both a GPS and a "
                "local position at different places."
            ),
        }
    result = {
        "available": True,
        "pairs": fit.pairs,
        "scale": fit.scale,
        "rotation_deg": math.degrees(fit.rotation),
        "rms_m": fit.rms,
        "corners": None,
    }
    if map_image is not None:
        result["corners"] = {
            name: list(reversed(fit.to_lon_lat(*xy)))  # [lat, lon] as Leaflet wants
            for name, xy in map_corners(map_image).items()
        }
    return result
