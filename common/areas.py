"""Search areas on the WGS84 globe, as the databases can test points against them.

PostGIS geometries and SpatiaLite are planar in degrees: a box or polygon drawn
across the antimeridian (a map lets the longitude run past 180°) must be cut at
±180° and its far part moved back by 360°, or the test would look at the other
side of the world.  Every place search builds its area here.
"""

import json
import math

from django.contrib.gis.gdal.error import GDALException
from django.contrib.gis.geos import GEOSException, GEOSGeometry, MultiPolygon, Polygon
from django.utils.translation import gettext

# A drawn area may run once around past either side of the antimeridian.
_LONGITUDE_REACH = 540.0
_WORLD = (-180.0, -90.0, 180.0, 90.0)
_SHIFTS = {0.0: _WORLD, -360.0: (180.0, -90.0, 540.0, 90.0), 360.0: (-540.0, -90.0, -180.0, 90.0)}
# Corners an area may have: checking validity and testing each row's point costs
# time with every corner. A test case's area drawn on a map has a few thousand.
MAX_CORNERS = 20_000


class AreaError(ValueError):
    """The text does not describe a usable area; the message says why."""


def area_from_box(west: float, south: float, east: float, north: float) -> MultiPolygon:
    """A box in degrees; ``west > east`` is a box across the antimeridian."""
    values = (west, south, east, north)
    if not all(math.isfinite(v) for v in values):
        raise AreaError(gettext("The box needs four finite numbers."))
    if not (-90 <= south < north <= 90):
        raise AreaError(gettext("The box needs south < north, both within ±90°."))
    if not all(-180 <= v <= 180 for v in (west, east)) or west == east:
        raise AreaError(gettext("The box needs two different longitudes within ±180°."))
    if west > east:
        east += 360.0
    return _on_the_globe(Polygon.from_bbox((west, south, east, north)))


def area_from_text(text: str) -> MultiPolygon:
    """A GeoJSON Polygon or MultiPolygon (a Feature's geometry too), or the same as WKT."""
    try:
        value = json.loads(text)
    except ValueError:
        value = None
    except RecursionError:
        raise AreaError(gettext("The area is nested too deeply to be a polygon.")) from None
    if isinstance(value, dict) and value.get("type") == "Feature":
        value = value.get("geometry")
    try:
        geometry = GEOSGeometry(json.dumps(value) if isinstance(value, dict) else text)
    except (GEOSException, GDALException, ValueError, TypeError):
        raise AreaError(gettext("Give the area as a GeoJSON or WKT polygon.")) from None
    if geometry.geom_type not in ("Polygon", "MultiPolygon"):
        raise AreaError(
            gettext("The area must be a polygon, not a %(kind)s.") % {"kind": geometry.geom_type}
        )
    corners = _corners(geometry)
    if corners > MAX_CORNERS:
        raise AreaError(
            gettext("The area has %(count)s corners; give at most %(max)s (simplify it).")
            % {"count": corners, "max": MAX_CORNERS}
        )
    if geometry.srid not in (None, 4326):
        raise AreaError(gettext("Give the area in WGS84 longitude and latitude."))
    xmin, ymin, xmax, ymax = geometry.extent
    if not all(math.isfinite(v) for v in geometry.extent):
        raise AreaError(gettext("The area's coordinates must be finite numbers."))
    if ymin < -90 or ymax > 90 or xmin < -_LONGITUDE_REACH or xmax > _LONGITUDE_REACH:
        raise AreaError(
            gettext("The area's latitudes must lie within ±90° and longitudes within ±540°.")
        )
    if not geometry.valid:
        raise AreaError(
            gettext("The area is not a valid polygon (%(reason)s).")
            % {"reason": geometry.valid_reason}
        )
    if geometry.empty or geometry.area == 0:
        raise AreaError(gettext("The area is empty."))
    return _on_the_globe(geometry)


def _corners(geometry) -> int:
    """Corners of a polygon or multipolygon: its points, less each ring's closing one."""
    polygons = [geometry] if geometry.geom_type == "Polygon" else list(geometry)
    return geometry.num_coords - sum(len(polygon) for polygon in polygons)


def _on_the_globe(geometry) -> MultiPolygon:
    """The area's parts within ±180°, each moved there by a whole turn."""
    pieces = []
    for shift, box in _SHIFTS.items():
        part = geometry.intersection(Polygon.from_bbox(box))
        for polygon in _polygons(part):
            pieces.append(_moved(polygon, shift))
    if not pieces:
        raise AreaError(gettext("The area is empty."))
    area = MultiPolygon(*pieces)
    area.srid = 4326
    return area


def _polygons(geometry) -> list[Polygon]:
    if geometry.empty:
        return []
    if geometry.geom_type == "Polygon":
        return [geometry] if geometry.area > 0 else []
    if geometry.geom_type in ("MultiPolygon", "GeometryCollection"):
        return [polygon for part in geometry for polygon in _polygons(part)]
    return []  # a line or point where the area only touches ±180°


def _moved(polygon: Polygon, shift: float) -> Polygon:
    if shift == 0.0:
        return Polygon(*[ring.coords for ring in polygon])
    rings = [tuple((x + shift, y) for x, y, *_ in ring.coords) for ring in polygon]
    return Polygon(*rings)
