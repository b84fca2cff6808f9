"""The local map is placed on the GPS map by a transform fitted to every tie point."""

import math

import pytest
from pyproj import Geod

from events.services import segments
from events.services.segments import GpsPosition, LocalPosition
from telemetry.models import MapImage
from telemetry.selectors import overlay

WGS84 = Geod(ellps="WGS84")
ORIGIN = (7.2, 50.6)


def to_gps(x, y, *, scale=1.0, rotation=0.0, shift=(0.0, 0.0)):
    """Where a local point lies on Earth if local = rotated, scaled, shifted east/north."""
    c, s = math.cos(rotation), math.sin(rotation)
    east = scale * (c * x - s * y) + shift[0]
    north = scale * (s * x + c * y) + shift[1]
    lon, lat, _ = WGS84.fwd(*ORIGIN, math.degrees(math.atan2(east, north)), math.hypot(east, north))
    return lon, lat, x, y


def test_exact_points_give_back_rotation_and_scale():
    local = [(0, 0), (100, 0), (100, 80), (-30, 50), (10, -60)]
    points = [to_gps(x, y, scale=1.02, rotation=math.radians(35), shift=(12, -7)) for x, y in local]
    fit = overlay.estimate(points)
    assert fit.pairs == 5
    assert fit.scale == pytest.approx(1.02, abs=1e-4)
    assert math.degrees(fit.rotation) == pytest.approx(35, abs=0.01)
    assert fit.rms < 0.01
    lon, lat = fit.to_lon_lat(100, 80)
    assert (lon, lat) == pytest.approx(points[2][:2], abs=1e-7)


def test_one_bad_fix_is_outvoted_by_the_others():
    # The original used only the first two segments: an error there skewed everything.
    local = [(0, 0), (50, 0), (100, 0), (100, 100), (0, 100), (50, 50)]
    rotation = math.radians(-20)
    points = [to_gps(x, y, rotation=rotation) for x, y in local]
    lon, lat, x, y = points[1]
    points[1] = to_gps(x + 5, y - 4, rotation=rotation)[:2] + (x, y)  # 6 m off
    fit = overlay.estimate(points)
    assert math.degrees(fit.rotation) == pytest.approx(-20, abs=2.0)
    assert fit.scale == pytest.approx(1.0, abs=0.03)
    assert 0.5 < fit.rms < 5


def test_too_few_or_coincident_tie_points_give_no_transform():
    assert overlay.estimate([to_gps(0, 0)]) is None
    assert overlay.estimate([to_gps(3, 4), to_gps(3, 4)]) is None


def test_map_corners_follow_origin_resolution_and_yaw():
    grid = MapImage(
        width=200, height=100, resolution=0.05, origin_x=-5, origin_y=2, origin_yaw=math.pi / 2
    )
    corners = overlay.map_corners(grid)
    assert corners["bottom_left"] == pytest.approx((-5, 2))
    # 10 m wide along the yawed x axis (pointing to +y), 5 m tall along -x.
    assert corners["top_right"] == pytest.approx((-5 - 5, 2 + 10))
    assert corners["top_left"] == pytest.approx((-5 - 5, 2))


@pytest.mark.django_db
def test_overlay_uses_master_segments_of_the_whole_shift(shift, leg):
    tie = [to_gps(x, y, rotation=math.radians(90)) for x, y in [(0, 0), (40, 0), (40, 30)]]
    for i, (lon, lat, x, y) in enumerate(tie):
        segments.report_mode(
            leg, "ito" if i % 2 else "auto", gps=GpsPosition(lon, lat), local=LocalPosition(x, y)
        )
    result = overlay.overlay(shift, None)
    assert result["available"] is True
    assert result["pairs"] == 3  # ITO children repeat their master's start and are not counted
    assert result["rotation_deg"] == pytest.approx(90, abs=0.01)


@pytest.mark.django_db
def test_overlay_explains_why_it_is_missing(shift, leg):
    segments.report_mode(leg, "auto", gps=GpsPosition(*ORIGIN))
    result = overlay.overlay(shift, None)
    assert result["available"] is False
    assert "at least two segments" in result["detail"]
