"""Warm tile rendering of a 5000 x 5000 px GeoTIFF orthophoto, against the 100 ms target.

Makes a 5000 x 5000 RGB GeoTIFF in UTM 32N (10 cm pixels, 256 px blocks,
overviews, like a drone orthophoto exported as a Cloud-Optimized GeoTIFF) in a
temporary folder, then renders Web Mercator tiles with the function the tile
view and the report use (basemaps.selectors.tiles.render_tile): one pass to
warm up, then the timed passes.  Needs no database.

    .venv/bin/python benchmarks/basemap_tiles.py [--size 5000] [--zoom 20] [--passes 3]
"""

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

import numpy as np  # noqa: E402
import rasterio  # noqa: E402
from django.conf import settings  # noqa: E402

from basemaps.files import inspect_file  # noqa: E402
from basemaps.grid import WEB_MERCATOR  # noqa: E402
from basemaps.models import BasemapLayer  # noqa: E402
from basemaps.selectors.tiles import render_tile  # noqa: E402
from tests.support.basemaps import CENTRE, utm_profile  # noqa: E402

TARGET_MS = 100.0


def make_orthophoto(path: Path, size: int, pixel_m: float) -> None:
    profile = utm_profile(size, pixel_m, CENTRE, compress="deflate")
    # Fields and tracks: smooth colour changes with some grain, not pure noise
    # (which no camera makes and which would make PNG encoding the whole cost).
    rng = np.random.default_rng(1)
    cols = np.arange(size)
    with rasterio.open(path, "w", **profile) as out:
        for row in range(0, size, 512):
            rows = np.arange(row, min(row + 512, size))[:, None]
            base = [
                90 + 60 * np.sin(cols / 300.0) + 0 * rows,
                120 + 50 * np.cos(rows / 220.0) + 0 * cols,
                70 + 40 * np.sin((cols + rows) / 500.0),
            ]
            grain = rng.integers(-12, 12, (3, len(rows), size))
            block = np.clip(np.stack(base) + grain, 0, 255).astype(np.uint8)
            out.write(block, window=rasterio.windows.Window(0, row, size, len(rows)))
        out.build_overviews([2, 4, 8, 16, 32], rasterio.enums.Resampling.average)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=5000)
    parser.add_argument("--pixel", type=float, default=0.1, help="metres per pixel")
    parser.add_argument("--zoom", type=int, nargs="*", default=[16, 18, 20])
    parser.add_argument("--passes", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        settings.MEDIA_ROOT = folder
        path = Path(folder) / "ortho.tif"
        started = time.perf_counter()
        make_orthophoto(path, args.size, args.pixel)
        print(f"made {args.size}x{args.size} GeoTIFF in {time.perf_counter() - started:.1f} s")
        facts = inspect_file(path)
        layer = BasemapLayer(kind=facts.kind, file="ortho.tif", max_zoom=facts.max_zoom)
        layer.west, layer.south, layer.east, layer.north = facts.bounds
        tms = WEB_MERCATOR
        for zoom in args.zoom:
            # Tiles around the middle: all inside the picture, none at its edge.
            west, south, east, north = facts.bounds
            dx, dy = (east - west) / 4, (north - south) / 4
            middle = (west + dx, south + dy, east - dx, north - dy)
            tiles = list(tms.tiles(*middle, [zoom]))[:64]
            for tile in tiles:  # warm: file open, caches filled
                render_tile(layer, tile.z, tile.x, tile.y)
            times = []
            for _ in range(args.passes):
                for tile in tiles:
                    t0 = time.perf_counter()
                    data = render_tile(layer, tile.z, tile.x, tile.y)
                    times.append((time.perf_counter() - t0) * 1000)
                    assert data, tile
            times.sort()
            p95 = times[int(0.95 * (len(times) - 1))]
            verdict = "meets" if p95 < TARGET_MS else "MISSES"
            print(
                f"zoom {zoom}: {len(tiles)} tiles x {args.passes}: median "
                f"{statistics.median(times):.1f} ms, p95 {p95:.1f} ms, max {times[-1]:.1f} ms "
                f"per PNG tile ({verdict} the {TARGET_MS:.0f} ms target)"
            )


if __name__ == "__main__":
    main()
