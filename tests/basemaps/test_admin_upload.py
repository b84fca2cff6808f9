"""Administrators upload basemaps in Django admin; a bad file is refused and nothing is kept."""

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.urls import reverse
from pmtiles.tile import TileType

from basemaps.models import BasemapLayer
from tests.support.accounts import staff_user
from tests.support.basemaps import archive_tiles, make_pmtiles, quadrant_geotiff
from tests.support.images import png

ADD = "admin:basemaps_basemaplayer_add"


def form(upload, **extra):
    data = {"name": "Field orthophoto", "key": "field", "file": upload, "url": ""}
    data.update({"attribution": "Drone flight", "min_zoom": 0, "max_zoom": 19, **extra})
    return data


def stored_files(media_root):
    folder = media_root / "basemaps"
    return sorted(folder.iterdir()) if folder.exists() else []


@pytest.fixture
def admin_client(client, db):
    client.force_login(staff_user("administrator"))
    return client


# A small limit sends even this test's file through a temporary file on disk.
@pytest.mark.parametrize("memory_limit", [10 * 2**20, 1024], ids=["in-memory", "streamed"])
def test_a_geotiff_upload_becomes_a_layer_with_bounds_from_the_file(
    admin_client, media_root, tmp_path, settings, memory_limit
):
    settings.FILE_UPLOAD_MAX_MEMORY_SIZE = memory_limit
    tif = quadrant_geotiff(tmp_path / "ortho.tif").read_bytes()
    response = admin_client.post(reverse(ADD), form(SimpleUploadedFile("ortho.tif", tif)))
    assert response.status_code == 302, response.content.decode()[:2000]
    layer = BasemapLayer.objects.get(key="field")
    assert layer.kind == "raster"
    assert 7.1 < layer.west < 7.12 < layer.east < 7.13
    assert layer.max_zoom > 18
    assert [p.name for p in stored_files(media_root)] == ["ortho.tif"]


@pytest.mark.parametrize(
    "name, content, message",
    [
        ("ortho.tif", b"II*\x00 this is not really a tiff" * 50, "Not a georeferenced raster"),
        ("photo.png", png(size=(64, 64)), "Not a georeferenced raster"),
        ("area.mbtiles", b"SQLite format 3\x00" + b"\x00" * 200, "not an MBTiles archive"),
        ("area.pmtiles", "cut-short", "A damaged PMTiles archive"),
        ("vector.pmtiles", "vector", "Only raster archives can be served; this one holds MVT"),
    ],
)
def test_a_file_that_is_no_basemap_is_refused_and_nothing_stored(
    admin_client, media_root, tmp_path, name, content, message
):
    if content == "cut-short":
        content = make_pmtiles(tmp_path / name, archive_tiles()).read_bytes()[:200]
    elif content == "vector":
        content = make_pmtiles(tmp_path / name, archive_tiles(), TileType.MVT).read_bytes()
    response = admin_client.post(reverse(ADD), form(SimpleUploadedFile(name, content)))
    assert response.status_code == 200
    assert message in response.content.decode()
    assert not BasemapLayer.objects.exists()
    assert stored_files(media_root) == []


def test_a_file_over_the_size_limit_is_refused(admin_client, media_root, tmp_path, settings):
    settings.FTT_BASEMAP_MAX_UPLOAD_MB = 0
    tif = quadrant_geotiff(tmp_path / "ortho.tif").read_bytes()
    response = admin_client.post(reverse(ADD), form(SimpleUploadedFile("ortho.tif", tif)))
    assert "basemaps may have at most 0 MB" in response.content.decode()
    assert not BasemapLayer.objects.exists()
    assert stored_files(media_root) == []


def test_an_external_url_layer_needs_no_file(admin_client, media_root, settings):
    settings.FTT_TILE_HOSTS = ["tile.example.org"]
    url = "https://tile.example.org/{z}/{x}/{y}.png"
    response = admin_client.post(reverse(ADD), form("", url=url))
    assert response.status_code == 302
    layer = BasemapLayer.objects.get(key="field")
    assert (layer.kind, layer.url, layer.bounds) == ("url", url, None)


def test_operators_may_look_but_not_add(client, db):
    client.force_login(staff_user("operator"))
    assert client.get(reverse(ADD)).status_code == 403
    assert client.get(reverse("admin:basemaps_basemaplayer_changelist")).status_code == 200
