"""One Web Mercator tile of a layer, as PNG or WebP bytes.

The tile view and the report both call ``render_tile``, so a map in the PDF is
drawn from the same pixels the GUI shows, without an HTTP request to itself.
"""

import io
import sqlite3
import struct
import threading
import zlib
from pathlib import Path

from cachetools import LRUCache
from django.conf import settings
from PIL import Image, UnidentifiedImageError
from pmtiles.reader import Reader as PMTilesReader
from rasterio.errors import RasterioError
from rio_tiler.errors import RioTilerError, TileOutsideBounds

from basemaps.grid import WEB_MERCATOR
from basemaps.mbtiles import MBTiles
from basemaps.models import BasemapLayer
from basemaps.pmtiles_source import DirectoryTooLarge, bounded_source
from basemaps.rasters import GeoTiffTiles, NotAGeoTiff

FORMATS = {"png": "PNG", "webp": "WEBP"}
OPEN_FILES = 8
# A stored tile larger than this, or picturing more pixels, is not drawn.
MAX_TILE_BYTES = 4 * 1024 * 1024
MAX_TILE_PIXELS = 2048 * 2048
# What a damaged or hostile file raises while a tile is read or decoded: that
# tile is missing (404), not a server error.
DAMAGED = (
    sqlite3.Error,
    RasterioError,
    RioTilerError,
    NotAGeoTiff,
    UnidentifiedImageError,
    Image.DecompressionBombError,
    zlib.error,
    OSError,
    ValueError,
    LookupError,
    SyntaxError,
    struct.error,
)

# Opening a GeoTIFF costs more than reading one tile from it, so each thread
# keeps its last few files open; rasterio datasets must not be shared by threads.
_local = threading.local()


class _OpenFiles(LRUCache):
    """A thread's open files by (path, modification time); beyond OPEN_FILES
    the least recently read one is closed."""

    def popitem(self):
        key, handle = super().popitem()
        handle.close()
        return key, handle

    def get_open(self, path: Path, opener):
        key = (str(path), path.stat().st_mtime_ns)
        handle = self.get(key)
        if handle is None:
            handle = self[key] = opener(path)
        return handle


def _open(path: Path, opener):
    if not hasattr(_local, "files"):
        _local.files = _OpenFiles(maxsize=OPEN_FILES)
    return _local.files.get_open(path, opener)


class _PMTiles:
    def __init__(self, path: Path):
        self.handle = path.open("rb")
        self.reader = PMTilesReader(bounded_source(self.handle))

    def get(self, z, x, y):
        try:
            return self.reader.get(z, x, y)
        except DirectoryTooLarge:
            return None  # refused at upload; a file swapped in since shows no tiles

    def close(self):
        self.handle.close()


def tile_in_bounds(layer: BasemapLayer, z: int, x: int, y: int) -> bool:
    if not (layer.min_zoom <= z <= layer.max_zoom and 0 <= x < 2**z and 0 <= y < 2**z):
        return False
    if layer.bounds is None:
        return True
    west, south, east, north = layer.bounds
    box = WEB_MERCATOR.bounds(x, y, z)
    return box.left < east and box.right > west and box.bottom < north and box.top > south


def render_tile(layer: BasemapLayer, z: int, x: int, y: int, fmt: str = "png") -> bytes | None:
    """The tile's image bytes, or None where the layer has nothing to show (or a
    damaged file has nothing that can be drawn). Raises TooCostly when an
    archive does not answer within FTT_TILE_SECONDS."""
    if not layer.served_by_ftt or not layer.file or not tile_in_bounds(layer, z, x, y):
        return None
    path = Path(layer.file.path)
    try:
        if layer.kind == BasemapLayer.RASTER:
            return _raster_tile(_open(path, GeoTiffTiles), z, x, y, fmt)
        data = _archive_tile(layer, path, z, x, y)
        if not data or len(data) > MAX_TILE_BYTES:
            return None
        if layer.tile_format == fmt:
            return bytes(data)
        return _converted(data, fmt)
    except DAMAGED:
        return None


def _raster_tile(reader, z, x, y, fmt) -> bytes | None:
    try:
        image = reader.tile(x, y, z)
    except TileOutsideBounds:
        return None
    # zlevel 1: tiles travel over the field LAN, where encoding time matters
    # more than the few bytes the default level saves.
    options = {"zlevel": 1} if fmt == "png" else {}
    return image.render(img_format=FORMATS[fmt], **options)


def _archive_tile(layer, path: Path, z, x, y):
    if layer.kind == BasemapLayer.MBTILES:
        rows = _open(path, MBTiles).query(
            "SELECT tile_data FROM tiles WHERE zoom_level=? AND tile_column=? AND tile_row=?",
            # MBTiles count rows from the south (TMS), tile URLs from the north.
            (z, x, 2**z - 1 - y),
            seconds=settings.FTT_TILE_SECONDS,
        )
        tile = rows[0][0] if rows else None
        # A text or number stored as a tile is no picture.
        return tile if isinstance(tile, bytes) else None
    return _open(path, _PMTiles).get(z, x, y)


def _converted(data: bytes, fmt: str) -> bytes | None:
    image = Image.open(io.BytesIO(data))
    # Checked before decoding: a small file may claim a huge picture.
    if image.width * image.height > MAX_TILE_PIXELS:
        return None
    out = io.BytesIO()
    image.save(out, format=FORMATS[fmt])
    return out.getvalue()
