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
from pathlib import Path

import morecantile
import numpy as np
import requests
from django.utils.translation import gettext
from PIL import Image

from basemaps.grid import TILE_SIZE, WEB_MERCATOR
from basemaps.models import BasemapLayer
from basemaps.selectors.tiles import render_tile

log = logging.getLogger(__name__)

MAX_ZOOM = 19
USER_AGENT = "FTT-field-test-report/1.0 (field test tool report generator)"


def _corner_tiles(west, south, east, north, zoom) -> tuple[morecantile.Tile, morecantile.Tile]:
    """The north-west and the south-east tile of a box."""
    return (
        WEB_MERCATOR.tile(west, north, zoom, truncate=True),
        WEB_MERCATOR.tile(east, south, zoom, truncate=True),
    )


def fit_zoom(west, south, east, north, max_tiles: int = 16, max_zoom: int = MAX_ZOOM) -> int:
    """Highest zoom at which the box needs at most ``max_tiles`` tiles."""
    for zoom in range(max_zoom, 0, -1):
        first, last = _corner_tiles(west, south, east, north, zoom)
        if (last.x - first.x + 1) * (last.y - first.y + 1) <= max_tiles:
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
        self.session = requests.Session()  # one connection for a report's tiles
        self.session.headers["User-Agent"] = USER_AGENT

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
        try:
            response = self.session.get(self.url.format(z=zoom, x=x, y=y), timeout=self.timeout)
        except requests.RequestException as exc:
            return self._unavailable(exc)
        if not response.ok:
            # The server is there but has no such tile: leave this one blank.
            log.info(gettext("tile %s/%s/%s: HTTP %s"), zoom, x, y, response.status_code)
            self.failed += 1
            return None
        data = response.content
        try:
            image = Image.open(io.BytesIO(data)).convert("RGB")
        except (OSError, ValueError) as exc:
            return self._unavailable(exc)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        self.fetched += 1
        return image

    def _unavailable(self, exc: Exception) -> None:
        log.warning(gettext("tile server unavailable (%s); drawing maps without tiles"), exc)
        self.available = False
        self.failed += 1

    def mosaic(self, west, south, east, north):
        """(RGB array, (west, south, east, north) of the array) or None without tiles."""
        if not self.url:
            return None
        zoom = fit_zoom(west, south, east, north, max_zoom=self.max_zoom)
        first, last = _corner_tiles(west, south, east, north, zoom)
        x0, y0, x1, y1 = first.x, first.y, last.x, last.y
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
        w, n = WEB_MERCATOR.ul(first)
        e, s = WEB_MERCATOR.bounds(last).right, WEB_MERCATOR.bounds(last).bottom
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
