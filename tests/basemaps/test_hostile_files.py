"""Basemap files are data, not programs; URL layers reach allowed tile servers only
(issue 31, findings 3 and 4)."""

import sqlite3
import struct
import time
import zlib

import pytest
import rasterio
from django.core.files.uploadedfile import SimpleUploadedFile
from django.core.management import CommandError, call_command
from django.urls import reverse

from basemaps.models import BasemapLayer
from basemaps.services import layers
from tests.support.accounts import staff_user
from tests.support.basemaps import archive_tiles, make_mbtiles, quadrant_geotiff, utm_profile

ADD = "admin:basemaps_basemaplayer_add"


def vrt_over(source) -> str:
    """A georeferenced one-band VRT whose pixels come from ``source`` (any path GDAL opens)."""
    return f"""<VRTDataset rasterXSize="64" rasterYSize="64">
  <SRS>EPSG:32632</SRS>
  <GeoTransform>370000, 1, 0, 5610000, 0, -1</GeoTransform>
  <VRTRasterBand dataType="Byte" band="1">
    <SimpleSource>
      <SourceFilename relativeToVRT="0">{source}</SourceFilename>
      <SourceBand>1</SourceBand>
    </SimpleSource>
  </VRTRasterBand>
</VRTDataset>
"""


@pytest.fixture
def admin_client(client, db):
    client.force_login(staff_user("administrator"))
    return client


def form(**fields):
    data = {"name": "Layer", "key": "layer", "url": "", "attribution": ""}
    return {**data, "min_zoom": 0, "max_zoom": 19, "enabled": "on", **fields}


def test_a_vrt_is_refused_in_admin_even_over_a_real_geotiff(admin_client, media_root, tmp_path):
    tif = quadrant_geotiff(tmp_path / "ortho.tif")
    upload = SimpleUploadedFile("ortho.vrt", vrt_over(tif).encode())
    response = admin_client.post(reverse(ADD), form(file=upload))
    assert response.status_code == 200
    assert "not a TIFF file" in response.content.decode()
    assert not BasemapLayer.objects.exists()


@pytest.mark.parametrize(
    "source",
    ["{vrt}", "/vsicurl/http://127.0.0.1:8099/ortho.tif", "/vsizip/{tif}.zip/ortho.tif"],
    ids=["vrt-file", "vsicurl", "vsizip"],
)
def test_ftt_basemap_import_refuses_vrts_and_gdal_virtual_paths(db, media_root, tmp_path, source):
    tif = quadrant_geotiff(tmp_path / "ortho.tif")
    vrt = tmp_path / "ortho.vrt"
    vrt.write_text(vrt_over(tif))
    with pytest.raises(CommandError, match="not a TIFF file|GDAL virtual path"):
        call_command("ftt_basemap", "import", source.format(vrt=vrt, tif=tif))
    assert not BasemapLayer.objects.exists()


@pytest.mark.parametrize(
    "url",
    [
        "http://127.0.0.1:8099/{z}/{x}/{y}.png",
        "http://[::1]/{z}/{x}/{y}.png",
        "http://169.254.169.254/{z}/{x}/{y}.png",
        "http://10.0.0.5/{z}/{x}/{y}.png",
        "http://localhost/{z}/{x}/{y}.png",
        "https://tiles.elsewhere.example/{z}/{x}/{y}.png",
        "https://user:pw@tile.openstreetmap.org/{z}/{x}/{y}.png",
    ],
)
def test_a_url_layer_must_name_an_allowed_tile_server(admin_client, settings, url):
    settings.FTT_TILE_HOSTS = ["tile.openstreetmap.org", "*.maps.example"]
    response = admin_client.post(reverse(ADD), form(url=url))
    assert response.status_code == 200
    assert "FTT_TILE_HOSTS" in response.content.decode() or "user name" in response.content.decode()
    assert not BasemapLayer.objects.exists()


@pytest.mark.parametrize(
    "url, allowed",
    [
        ("https://tile.openstreetmap.org/{z}/{x}/{y}.png", ["tile.openstreetmap.org"]),
        ("https://a.maps.example/{z}/{x}/{y}.png", ["*.maps.example"]),
        # A field server on the LAN, named by the administrator.
        ("http://10.0.0.5:8080/{z}/{x}/{y}.png", ["10.0.0.5"]),
    ],
)
def test_an_allowed_tile_server_is_accepted(admin_client, settings, url, allowed):
    settings.FTT_TILE_HOSTS = allowed
    response = admin_client.post(reverse(ADD), form(url=url))
    assert response.status_code == 302, response.content.decode()[:3000]
    assert BasemapLayer.objects.get().url == url


# --- Hostile files that are real archives (finding 12) ---


def png_claiming(width: int, height: int) -> bytes:
    """A small PNG whose header claims a picture of width x height (a decompression bomb)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    pixels = zlib.compress(b"\x00" * 1024)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")
    )


@pytest.fixture
def archive(db, media_root, tmp_path):
    """A registered MBTiles layer and its tiles' addresses."""
    tiles = archive_tiles()
    layer = layers.register_file(make_mbtiles(tmp_path / "area.mbtiles", tiles), name="Area")
    return layer, sorted(tiles)


def tile_url(layer, tile, fmt="png"):
    z, x, y = tile
    return f"/tiles/{layer.key}/{z}/{x}/{y}.{fmt}"


def test_an_mbtiles_with_a_zoom_that_is_no_number_is_refused_on_upload(
    admin_client, media_root, tmp_path
):
    path = make_mbtiles(tmp_path / "area.mbtiles", archive_tiles())
    with sqlite3.connect(path) as db:
        db.execute("UPDATE metadata SET value = 'abc' WHERE name = 'minzoom'")
    upload = SimpleUploadedFile("area.mbtiles", path.read_bytes())
    response = admin_client.post(reverse(ADD), form(file=upload))
    assert response.status_code == 200
    assert "minzoom is &#x27;abc&#x27;, not a zoom level" in response.content.decode()
    assert not BasemapLayer.objects.exists()


def test_undecodable_and_bomb_tiles_are_missing_not_errors(archive, viewer_client):
    layer, (first, second, *_) = archive
    with sqlite3.connect(layer.file.path) as db:
        for (z, x, y), data in ((first, b"\x89PNG broken"), (second, png_claiming(10**5, 10**5))):
            where = "zoom_level=? AND tile_column=? AND tile_row=?"
            db.execute(f"UPDATE tiles SET tile_data = ? WHERE {where}", (data, z, x, 2**z - 1 - y))
    for tile in (first, second):
        assert viewer_client.get(tile_url(layer, tile, "webp")).status_code == 404


def test_a_tile_from_an_archive_that_will_not_answer_is_503_within_its_budget(
    archive, viewer_client, settings
):
    settings.FTT_TILE_SECONDS = 0.5
    layer, (tile, *_) = archive
    with sqlite3.connect(layer.file.path) as db:
        db.executescript(
            """
            ALTER TABLE tiles RENAME TO stored;
            CREATE VIEW tiles AS
              WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 1e12)
              SELECT zoom_level, tile_column, tile_row, tile_data FROM stored, n WHERE i = 1e12;
            """
        )
    started = time.monotonic()
    response = viewer_client.get(tile_url(layer, tile))
    assert response.status_code == 503
    assert response["Retry-After"]
    assert time.monotonic() - started < 3


def test_a_huge_geotiff_without_overviews_is_refused(db, media_root, tmp_path):
    path = tmp_path / "huge.tif"
    profile = utm_profile(20_000, 0.5, count=1, sparse_ok=True)
    with rasterio.open(path, "w", **profile):
        pass  # sparse: no block written, a small file picturing 400 million pixels
    with pytest.raises(CommandError, match="add overviews first"):
        call_command("ftt_basemap", "import", str(path))
    assert not BasemapLayer.objects.exists()


@pytest.mark.parametrize("fmt", ["png", "webp"])
def test_a_tile_stored_as_text_is_missing_not_an_error(archive, viewer_client, fmt):
    layer, (first, *_) = archive
    z, x, y = first
    with sqlite3.connect(layer.file.path) as db:
        where = "zoom_level=? AND tile_column=? AND tile_row=?"
        db.execute(f"UPDATE tiles SET tile_data = ? WHERE {where}", ("tile", z, x, 2**z - 1 - y))
    assert viewer_client.get(tile_url(layer, first, fmt)).status_code == 404
