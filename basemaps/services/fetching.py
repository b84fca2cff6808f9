"""Download the tiles of an area once, while online, into an archive FTT serves offline.

Tiles go into an MBTiles file as they arrive, so an interrupted download resumes
where it stopped: tiles already in the file are not asked for again.  A PMTiles
target is written from that file at the end (pmtiles' own converter).

Public tile servers limit bulk downloads (e.g. the OpenStreetMap tile usage
policy): requests are paced to a rate, identify FTT in their User-Agent, wait
when the server answers 429/503 with Retry-After, and the number of tiles is
capped unless raised on purpose.
"""

import io
import os
import sqlite3
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import morecantile
import requests
from django.utils.translation import gettext
from PIL import Image
from pmtiles.convert import mbtiles_to_pmtiles

from basemaps.grid import WEB_MERCATOR

USER_AGENT = "FTT-field-test-tool/1.0 (offline basemap preparation; ftt_basemap fetch)"
FORMATS = {"PNG": "png", "JPEG": "jpg", "WEBP": "webp"}
# The PMTiles converter spells JPEG the long way.
CONVERTER_FORMATS = {"jpg": "jpeg"}
MAX_WAIT_S = 300


class FetchError(Exception):
    """The download stopped; what was fetched is kept for the next run."""


@dataclass
class FetchResult:
    path: Path
    total: int
    fetched: int
    already_there: int
    missing: int


def parse_zooms(text: str) -> list[int]:
    low, _, high = text.partition("-")
    zooms = list(range(int(low), int(high or low) + 1))
    if not zooms or zooms[0] < 0 or zooms[-1] > 24:
        raise ValueError(f"zooms {text!r}: give e.g. 14-19, between 0 and 24")
    return zooms


def area_tiles(bbox, zooms) -> list[morecantile.Tile]:
    west, south, east, north = bbox
    if not (west < east and south < north):
        raise ValueError("bbox: give west,south,east,north in degrees")
    return list(WEB_MERCATOR.tiles(west, south, east, north, zooms))


def _open_staging(path: Path) -> sqlite3.Connection:
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE IF NOT EXISTS metadata (name TEXT PRIMARY KEY, value TEXT)")
    db.execute(
        "CREATE TABLE IF NOT EXISTS tiles (zoom_level INTEGER, tile_column INTEGER, "
        "tile_row INTEGER, tile_data BLOB, PRIMARY KEY (zoom_level, tile_column, tile_row))"
    )
    return db


class _Pace:
    def __init__(self, rate: float):
        self.interval = 1.0 / rate if rate > 0 else 0.0
        self.next = 0.0

    def wait(self, at_least: float = 0.0):
        now = time.monotonic()
        delay = max(self.next - now, at_least)
        if delay > 0:
            time.sleep(delay)
        self.next = time.monotonic() + self.interval


def _retry_after(response) -> float:
    try:
        return min(float(response.headers.get("Retry-After", "5")), MAX_WAIT_S)
    except ValueError:
        return 5.0


def fetch_area(
    url: str,
    bbox,
    zooms: list[int],
    out: Path,
    *,
    rate: float,
    max_tiles: int,
    retries: int = 3,
    attribution: str = "",
    progress: Callable[[int, int], None] = lambda done, total: None,
) -> FetchResult:
    out = Path(out)
    if out.suffix not in (".mbtiles", ".pmtiles"):
        raise ValueError("the output must end in .mbtiles or .pmtiles")
    tiles = area_tiles(bbox, zooms)
    if len(tiles) > max_tiles:
        raise ValueError(
            f"{len(tiles)} tiles is more than --max-tiles {max_tiles}; public tile servers "
            "forbid bulk downloads, so choose a smaller area or fewer zooms, or raise the "
            "limit for a server that allows it"
        )
    staging = out if out.suffix == ".mbtiles" else out.with_name(out.name + ".part.mbtiles")
    db = _open_staging(staging)
    have = {tuple(row) for row in db.execute("SELECT zoom_level, tile_column, tile_row FROM tiles")}
    pace = _Pace(rate)
    session = requests.Session()
    session.headers["User-Agent"] = USER_AGENT
    fetched = missing = already = 0
    tile_format = dict(db.execute("SELECT name, value FROM metadata")).get("format")
    try:
        for done, tile in enumerate(tiles, start=1):
            key = (tile.z, tile.x, 2**tile.z - 1 - tile.y)
            if key in have:
                already += 1
            else:
                data = _get(session, pace, url.format(z=tile.z, x=tile.x, y=tile.y), retries)
                if data is None:
                    missing += 1
                else:
                    found = FORMATS.get(Image.open(io.BytesIO(data)).format, "png")
                    tile_format = tile_format or found
                    db.execute("INSERT OR REPLACE INTO tiles VALUES (?, ?, ?, ?)", (*key, data))
                    db.commit()
                    fetched += 1
            progress(done, len(tiles))
        west, south, east, north = bbox
        meta = {
            "name": out.stem,
            "format": tile_format or "png",
            "bounds": f"{west},{south},{east},{north}",
            "minzoom": str(min(zooms)),
            "maxzoom": str(max(zooms)),
            "attribution": attribution,
            "type": "baselayer",
        }
        db.executemany("INSERT OR REPLACE INTO metadata VALUES (?, ?)", meta.items())
        db.commit()
    finally:
        db.close()
    if out.suffix == ".pmtiles":
        _to_pmtiles(staging, out, meta["format"])
    return FetchResult(out, len(tiles), fetched, already, missing)


def _to_pmtiles(staging: Path, out: Path, tile_format: str) -> None:
    with sqlite3.connect(staging) as db:
        db.execute(
            "UPDATE metadata SET value=? WHERE name='format'",
            (CONVERTER_FORMATS.get(tile_format, tile_format),),
        )
    db.close()
    part = out.with_name(out.name + ".part")
    mbtiles_to_pmtiles(str(staging), str(part), None)
    os.replace(part, out)
    staging.unlink()


def _get(session, pace: _Pace, url: str, retries: int) -> bytes | None:
    wait = 0.0
    for attempt in range(retries + 1):
        pace.wait(wait)
        try:
            response = session.get(url, timeout=20)
        except requests.RequestException as exc:
            if attempt == retries:
                raise FetchError(f"{url}: {exc}") from exc
            wait = 2.0**attempt
            continue
        if response.status_code == 200:
            return response.content
        if response.status_code in (404, 204):
            return None
        if attempt == retries:
            raise FetchError(
                gettext("%(url)s: HTTP %(status)s") % {"url": url, "status": response.status_code}
            )
        wait = _retry_after(response) if response.status_code in (429, 503) else 2.0**attempt
    return None
