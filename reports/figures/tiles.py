"""Slippy-map tiles for report maps: fetched politely, cached on disk, or drawn by FTT.

Tiles are cached under ``<cache>/<hash of the URL template>/z/x/y.png`` and a
cached tile is never fetched again.  The first tile that cannot be fetched
because the server is unreachable marks the whole source unavailable for the
rest of the report, so a report made offline does not wait on every tile.

``LayerTiles`` draws the tiles of one of FTT's own basemap layers with the
function the tile view uses, so the report needs neither network nor its own
web server.
"""

import hashlib
import io
import logging
import math
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
from django.utils.translation import gettext
from PIL import Image

from basemaps.models import BasemapLayer
from basemaps.selectors.tiles import render_tile

log = logging.getLogger(__name__)

TILE_SIZE = 256
MAX_ZOOM = 19
USER_AGENT = "FTT-field-test-report/1.0 (field test tool report generator)"


def lonlat_to_tile(lon: float, lat: float, zoom: int) -> tuple[float, float]:
    """Fractional tile coordinates (Web Mercator, origin at the north-west)."""
    lat = max(min(lat, 85.0511), -85.0511)
    n = 2.0**zoom
    x = (lon + 180.0) / 360.0 * n
    y = (1.0 - math.asinh(math.tan(math.radians(lat))) / math.pi) / 2.0 * n
    return x, y


def tile_to_lonlat(x: float, y: float, zoom: int) -> tuple[float, float]:
    n = 2.0**zoom
    lon = x / n * 360.0 - 180.0
    lat = math.degrees(math.atan(math.sinh(math.pi * (1 - 2 * y / n))))
    return lon, lat


def fit_zoom(west, south, east, north, max_tiles: int = 16, max_zoom: int = MAX_ZOOM) -> int:
    """Highest zoom at which the box needs at most ``max_tiles`` tiles."""
    for zoom in range(max_zoom, 0, -1):
        x0, y0 = lonlat_to_tile(west, north, zoom)
        x1, y1 = lonlat_to_tile(east, south, zoom)
        count = (int(x1) - int(x0) + 1) * (int(y1) - int(y0) + 1)
        if count <= max_tiles:
            return zoom
    return 1


class TileSource:
    def __init__(
        self, url: str | None, cache_dir: Path, timeout: float = 5.0, max_zoom: int = MAX_ZOOM
    ):
        self.url = url
        self.max_zoom = max_zoom
        self.timeout = timeout
        key = hashlib.sha256((url or "").encode()).hexdigest()[:16]
        self.cache_dir = Path(cache_dir) / key
        self.available = bool(url)
        self.fetched = 0
        self.from_cache = 0
        self.failed = 0

    def tile(self, zoom: int, x: int, y: int) -> Image.Image | None:
        n = 2**zoom
        if not 0 <= y < n:
            return None
        x %= n
        path = self.cache_dir / str(zoom) / str(x) / f"{y}.png"
        if path.exists():
            self.from_cache += 1
            return Image.open(path).convert("RGB")
        if not self.available:
            return None
        request = urllib.request.Request(
            self.url.format(z=zoom, x=x, y=y), headers={"User-Agent": USER_AGENT}
        )
        try:
            with urllib.request.urlopen(request, timeout=self.timeout) as response:
                data = response.read()
            image = Image.open(io.BytesIO(data)).convert("RGB")
        except urllib.error.HTTPError as exc:
            # The server is there but has no such tile: leave this one blank.
            log.info(gettext("tile %s/%s/%s: HTTP %s"), zoom, x, y, exc.code)
            self.failed += 1
            return None
        except (OSError, ValueError) as exc:
            log.warning(gettext("tile server unavailable (%s); drawing maps without tiles"), exc)
            self.available = False
            self.failed += 1
            return None
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        self.fetched += 1
        return image

    def mosaic(self, west, south, east, north):
        """(RGB array, (west, south, east, north) of the array) or None without tiles."""
        if not self.url:
            return None
        zoom = fit_zoom(west, south, east, north, max_zoom=self.max_zoom)
        fx0, fy0 = lonlat_to_tile(west, north, zoom)
        fx1, fy1 = lonlat_to_tile(east, south, zoom)
        x0, y0, x1, y1 = int(fx0), int(fy0), int(fx1), int(fy1)
        canvas = Image.new("RGB", ((x1 - x0 + 1) * TILE_SIZE, (y1 - y0 + 1) * TILE_SIZE), "white")
        any_tile = False
        for tx in range(x0, x1 + 1):
            for ty in range(y0, y1 + 1):
                tile = self.tile(zoom, tx, ty)
                if tile is not None:
                    any_tile = True
                    if tile.size != (TILE_SIZE, TILE_SIZE):
                        tile = tile.resize((TILE_SIZE, TILE_SIZE))
                    canvas.paste(tile, ((tx - x0) * TILE_SIZE, (ty - y0) * TILE_SIZE))
        if not any_tile:
            return None
        w, n = tile_to_lonlat(x0, y0, zoom)
        e, s = tile_to_lonlat(x1 + 1, y1 + 1, zoom)
        return np.asarray(canvas), (w, s, e, n), zoom


class LayerTiles(TileSource):
    def __init__(self, layer: BasemapLayer, max_zoom: int = MAX_ZOOM):
        super().__init__(None, Path(), max_zoom=min(max_zoom, layer.max_zoom))
        self.layer = layer
        # mosaic() and the report's credits read ``url``: name the layer instead.
        self.url = f"basemap \u201c{layer.name}\u201d" + (
            f" ({layer.attribution})" if layer.attribution else ""
        )
        self.available = True

    def tile(self, zoom: int, x: int, y: int) -> Image.Image | None:
        data = render_tile(self.layer, zoom, x, y)
        if data is None:
            return None
        self.fetched += 1
        # Outside the orthophoto the tile is transparent: white, like the page.
        image = Image.open(io.BytesIO(data)).convert("RGBA")
        page = Image.new("RGBA", image.size, "white")
        return Image.alpha_composite(page, image).convert("RGB")
