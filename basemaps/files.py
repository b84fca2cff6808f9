"""What a basemap file is: kind, bounds and zooms, read with the format's own library.

``inspect_file`` refuses anything that is not a georeferenced raster or a raster
tile archive, with a message for the person who uploaded it.
"""

import math
import sqlite3
import warnings
from dataclasses import dataclass
from pathlib import Path

from django.core.exceptions import ValidationError
from pmtiles.reader import Reader as PMTilesReader
from pmtiles.tile import TileType
from rasterio.errors import NotGeoreferencedWarning, RasterioError
from rio_tiler.errors import RioTilerError

from basemaps.mbtiles import MBTiles, TooCostly
from basemaps.models.layers import MAX_ZOOM, BasemapLayer
from basemaps.pmtiles_source import DirectoryTooLarge, bounded_source, check_unpacked_size
from basemaps.rasters import GeoTiffTiles, NotAGeoTiff, check_local_file, open_geotiff

SQLITE_MAGIC = b"SQLite format 3\x00"
PMTILES_MAGIC = b"PMTiles"
PMTILES_PARTS = ("root", "metadata", "leaf_directory", "tile_data")
RASTER_TILE_TYPES = {TileType.PNG: "png", TileType.JPEG: "jpg", TileType.WEBP: "webp"}
# Seconds an archive's metadata and zoom range may take to read on upload.
CHECK_SECONDS = 10
# A zoomed-out tile is drawn from the coarsest overview (or the image itself):
# one larger than this a side would take seconds per tile.
MAX_COARSEST_SIDE = 8192
# Beyond its native resolution a raster is still drawn, enlarged, for a few zooms.
OVERZOOM = 3


@dataclass
class FileFacts:
    kind: str
    bounds: tuple[float, float, float, float]  # west, south, east, north in degrees
    min_zoom: int
    max_zoom: int
    tile_format: str = ""


def refuse(message: str):
    raise ValidationError(message, code="not_a_basemap")


def local_file(path) -> Path:
    """``path`` as a regular local file; refused for a GDAL virtual path or an address."""
    try:
        return check_local_file(path)
    except NotAGeoTiff as exc:
        refuse(str(exc))


def inspect_file(path) -> FileFacts:
    path = local_file(path)
    with path.open("rb") as f:
        head = f.read(16)
    if head.startswith(SQLITE_MAGIC):
        return _mbtiles(path)
    if head.startswith(PMTILES_MAGIC):
        return _pmtiles(path)
    return _raster(path)


def _raster(path: Path) -> FileFacts:
    try:
        # A plain image is expected here and answered below; no warning in the log.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            dataset = open_geotiff(path)
        with dataset:
            if dataset.crs is None or dataset.transform.is_identity:
                refuse(
                    "This image has no georeference (no coordinate system or position); "
                    "export it as a GeoTIFF with its CRS."
                )
            if dataset.count not in (1, 3, 4):
                refuse(f"Need 1 (grey), 3 (RGB) or 4 (RGBA) bands, not {dataset.count}.")
            if set(dataset.dtypes) != {"uint8"}:
                refuse(f"Need 8-bit bands, not {', '.join(sorted(set(dataset.dtypes)))}.")
            coarsest = max(dataset.overviews(1), default=1)
            if max(dataset.width, dataset.height) / coarsest > MAX_COARSEST_SIDE:
                refuse(
                    f"{dataset.width} x {dataset.height} pixels, and no overview of at most "
                    f"{MAX_COARSEST_SIDE} pixels a side to draw the whole area from; add "
                    "overviews first (gdaladdo -r average FILE, or export a COG)."
                )
        with GeoTiffTiles(path) as tiles:
            reader = tiles.reader
            bounds = tuple(reader.get_geographic_bounds(reader.tms.rasterio_geographic_crs))
            low, high = reader.minzoom, reader.maxzoom
    except (NotAGeoTiff, RasterioError, RioTilerError) as exc:
        refuse(
            "Not a georeferenced raster (GeoTIFF) nor an MBTiles or PMTiles archive "
            f"({str(exc).splitlines()[0][:200]})."
        )
    # Zoomed out, the orthophoto is still drawn (small, from its overviews), so a
    # map of a whole test area shows it too; the file's own minimum is not a limit.
    return FileFacts(BasemapLayer.RASTER, bounds, 0, min(MAX_ZOOM, max(high, low) + OVERZOOM))


def _zoom(meta: dict, name: str, found: int) -> int:
    raw = meta.get(name, found)
    try:
        zoom = int(raw)
    except (TypeError, ValueError):
        refuse(f"This MBTiles archive's {name} is {str(raw)[:40]!r}, not a zoom level.")
    if not 0 <= zoom <= MAX_ZOOM:
        refuse(f"This MBTiles archive's {name} is {zoom}; zoom levels go from 0 to {MAX_ZOOM}.")
    return zoom


def _mbtiles(path: Path) -> FileFacts:
    try:
        with MBTiles(path) as archive:
            meta = dict(archive.query("SELECT name, value FROM metadata", seconds=CHECK_SECONDS))
            (zooms,) = archive.query(
                "SELECT min(zoom_level), max(zoom_level) FROM tiles", seconds=CHECK_SECONDS
            )
    except sqlite3.Error as exc:
        refuse(f"An SQLite file, but not an MBTiles archive ({exc}).")
    except TooCostly as exc:
        refuse(f"This MBTiles archive is too slow to read ({exc}).")
    fmt = str(meta.get("format", "png")).lower().replace("jpeg", "jpg")
    if fmt not in ("png", "jpg", "webp"):
        refuse(f"Only raster archives can be served; this one holds {fmt[:40]!r} tiles.")
    if zooms[0] is None:
        refuse("This MBTiles archive holds no tiles.")
    try:
        bounds = tuple(float(v) for v in str(meta["bounds"]).split(","))
    except (KeyError, ValueError):
        refuse("This MBTiles archive has no bounds in its metadata.")
    if len(bounds) != 4 or not all(math.isfinite(v) for v in bounds):
        refuse("This MBTiles archive has malformed bounds in its metadata.")
    low, high = _zoom(meta, "minzoom", zooms[0]), _zoom(meta, "maxzoom", zooms[1])
    if low > high:
        refuse(f"This MBTiles archive's minzoom {low} is above its maxzoom {high}.")
    return FileFacts(BasemapLayer.MBTILES, bounds, low, high, fmt)


def _pmtiles(path: Path) -> FileFacts:
    size = path.stat().st_size
    try:
        with path.open("rb") as f:
            source = bounded_source(f)
            header = PMTilesReader(source).header()
            # A copy cut short still has a good header; its directories and tiles are missing.
            ends = [header[f"{part}_offset"] + header[f"{part}_length"] for part in PMTILES_PARTS]
            if max(ends) > size:
                refuse(f"A damaged PMTiles archive: {size} bytes of the {max(ends)} it needs.")
            check_unpacked_size(source(header["root_offset"], header["root_length"]))
    except DirectoryTooLarge:
        refuse("This PMTiles archive's directory unpacks to more than it can hold (a gzip bomb?).")
    except ValidationError:
        raise
    except Exception as exc:  # noqa: BLE001 - the library raises bare errors on bad files
        refuse(f"A damaged PMTiles archive ({exc}).")
    fmt = RASTER_TILE_TYPES.get(header["tile_type"])
    if fmt is None:
        refuse(f"Only raster archives can be served; this one holds {header['tile_type'].name}.")
    bounds = tuple(
        header[k] / 1e7 for k in ("min_lon_e7", "min_lat_e7", "max_lon_e7", "max_lat_e7")
    )
    return FileFacts(BasemapLayer.PMTILES, bounds, header["min_zoom"], header["max_zoom"], fmt)
