"""Basemap files made in the test: a quadrant GeoTIFF in UTM 32N and small tile archives."""

import io
import sqlite3
from pathlib import Path

import numpy as np
import rasterio
from PIL import Image
from pmtiles.tile import Compression, TileType, zxy_to_tileid
from pmtiles.writer import Writer
from pyproj import Transformer
from rasterio.transform import from_origin

from basemaps.grid import WEB_MERCATOR

# Near Wachtberg; the quadrants' colours, clockwise from the north-west.
CENTRE = (7.12, 50.61)
# Colours no chart or track line of the report uses.
QUADRANTS = {
    "nw": (230, 20, 230),
    "ne": (20, 210, 220),
    "se": (250, 230, 20),
    "sw": (30, 60, 220),
}
UTM32N = "EPSG:32632"


def utm_zone(lon: float, lat: float) -> str:
    return f"EPSG:{(32600 if lat >= 0 else 32700) + int((lon + 180) // 6) + 1}"


def utm_profile(size: int, pixel_m: float, centre=CENTRE, **extra) -> dict:
    """Rasterio profile of a square, tiled 8-bit RGB GeoTIFF in UTM centred on ``centre``."""
    crs = utm_zone(*centre)
    east, north = Transformer.from_crs("EPSG:4326", crs, always_xy=True).transform(*centre)
    half = size * pixel_m / 2
    return {
        "driver": "GTiff",
        "width": size,
        "height": size,
        "count": 3,
        "dtype": "uint8",
        "crs": crs,
        "transform": from_origin(east - half, north + half, pixel_m, pixel_m),
        "tiled": True,
        "blockxsize": 256,
        "blockysize": 256,
        **extra,
    }


def quadrant_geotiff(path: Path, size: int = 512, pixel_m: float = 0.5, centre=CENTRE) -> Path:
    """RGB GeoTIFF in UTM (32N for CENTRE) around ``centre``, one colour per quadrant."""
    half = size // 2
    rgb = np.zeros((3, size, size), dtype=np.uint8)
    for (rows, cols), name in (
        ((slice(0, half), slice(0, half)), "nw"),
        ((slice(0, half), slice(half, None)), "ne"),
        ((slice(half, None), slice(half, None)), "se"),
        ((slice(half, None), slice(0, half)), "sw"),
    ):
        for band, value in enumerate(QUADRANTS[name]):
            rgb[band, rows, cols] = value
    profile = utm_profile(size, pixel_m, centre)
    with rasterio.open(path, "w", **profile) as out:
        out.write(rgb)
        if size >= 1024:
            out.build_overviews([2, 4, 8, 16])
    return path


def quadrant_point(name: str, offset_m: float = 50.0) -> tuple[float, float]:
    """lon, lat of a point ``offset_m`` into a quadrant, diagonally from the centre."""
    east, north = Transformer.from_crs("EPSG:4326", UTM32N, always_xy=True).transform(*CENTRE)
    dx = offset_m if name in ("ne", "se") else -offset_m
    dy = offset_m if name in ("nw", "ne") else -offset_m
    back = Transformer.from_crs(UTM32N, "EPSG:4326", always_xy=True)
    return back.transform(east + dx, north + dy)


def tile_and_pixel(lon: float, lat: float, z: int) -> tuple[tuple[int, int, int], tuple[int, int]]:
    """(z, x, y) of the tile holding a point and the point's pixel in that tile."""
    tile = WEB_MERCATOR.tile(lon, lat, z)
    box = WEB_MERCATOR.xy_bounds(tile)
    x, y = WEB_MERCATOR.xy(lon, lat)
    px = int((x - box.left) / (box.right - box.left) * 256)
    py = int((box.top - y) / (box.top - box.bottom) * 256)
    return (z, tile.x, tile.y), (px, py)


def colour_at(data: bytes, pixel) -> tuple[int, ...]:
    return Image.open(io.BytesIO(data)).convert("RGBA").getpixel(pixel)


def near(colour, expected, tolerance=12) -> bool:
    return all(abs(a - b) <= tolerance for a, b in zip(colour, expected, strict=False))


def solid_png(colour) -> bytes:
    out = io.BytesIO()
    Image.new("RGB", (256, 256), colour).save(out, "PNG")
    return out.getvalue()


def archive_tiles(z: int = 12) -> dict[tuple[int, int, int], tuple[int, int, int]]:
    """Four tiles around CENTRE, each in one quadrant colour."""
    centre = WEB_MERCATOR.tile(*CENTRE, z)
    colours = list(QUADRANTS.values())
    return {
        (z, centre.x + dx, centre.y + dy): colours[2 * dy + dx] for dx in (0, 1) for dy in (0, 1)
    }


def _bounds(tiles) -> tuple[float, float, float, float]:
    boxes = [WEB_MERCATOR.bounds(x, y, z) for z, x, y in tiles]
    return (
        min(b.left for b in boxes),
        min(b.bottom for b in boxes),
        max(b.right for b in boxes),
        max(b.top for b in boxes),
    )


def make_mbtiles(path: Path, tiles) -> Path:
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE metadata (name TEXT, value TEXT)")
    db.execute(
        "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, "
        "tile_data BLOB)"
    )
    zooms = [z for z, _, _ in tiles]
    meta = {
        "name": "test",
        "format": "png",
        "bounds": ",".join(str(v) for v in _bounds(tiles)),
        "minzoom": str(min(zooms)),
        "maxzoom": str(max(zooms)),
    }
    db.executemany("INSERT INTO metadata VALUES (?, ?)", meta.items())
    db.executemany(
        "INSERT INTO tiles VALUES (?, ?, ?, ?)",
        [(z, x, 2**z - 1 - y, solid_png(c)) for (z, x, y), c in tiles.items()],
    )
    db.commit()
    db.close()
    return path


def make_pmtiles(path: Path, tiles, tile_type=TileType.PNG) -> Path:
    west, south, east, north = _bounds(tiles)
    zooms = [z for z, _, _ in tiles]
    with path.open("wb") as f:
        writer = Writer(f)
        for (z, x, y), colour in sorted(tiles.items(), key=lambda t: zxy_to_tileid(*t[0])):
            writer.write_tile(zxy_to_tileid(z, x, y), solid_png(colour))
        writer.finalize(
            {
                "tile_type": tile_type,
                "tile_compression": Compression.NONE,
                "min_zoom": min(zooms),
                "max_zoom": max(zooms),
                "min_lon_e7": int(west * 1e7),
                "min_lat_e7": int(south * 1e7),
                "max_lon_e7": int(east * 1e7),
                "max_lat_e7": int(north * 1e7),
                "center_zoom": min(zooms),
                "center_lon_e7": int(CENTRE[0] * 1e7),
                "center_lat_e7": int(CENTRE[1] * 1e7),
            },
            {"attribution": "test"},
        )
    return path
