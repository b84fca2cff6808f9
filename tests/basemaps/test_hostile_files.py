"""Basemap files are data, not programs; URL layers reach allowed tile servers only
(issue 31, findings 3 and 4)."""

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from django.core.management import CommandError, call_command
from django.urls import reverse

from basemaps.models import BasemapLayer
from tests.support.accounts import staff_user
from tests.support.basemaps import quadrant_geotiff

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
