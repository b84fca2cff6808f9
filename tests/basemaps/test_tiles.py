"""Tiles FTT serves from its own layers: the right colours in the right place, nothing outside."""

import pytest
from django.urls import reverse

from basemaps.services import layers
from tests.support.basemaps import (
    QUADRANTS,
    archive_tiles,
    colour_at,
    make_mbtiles,
    make_pmtiles,
    near,
    quadrant_point,
    tile_and_pixel,
)


def tile_url(layer, z, x, y, fmt="png"):
    return reverse("basemap-tile", kwargs={"key": layer.key, "z": z, "x": x, "y": y, "fmt": fmt})


@pytest.mark.parametrize("fmt", ["png", "webp"])
@pytest.mark.parametrize("quadrant", list(QUADRANTS))
def test_each_quadrant_of_a_utm_geotiff_shows_its_colour(viewer_client, orthophoto, quadrant, fmt):
    (z, x, y), pixel = tile_and_pixel(*quadrant_point(quadrant), 19)
    response = viewer_client.get(tile_url(orthophoto, z, x, y, fmt))
    assert response.status_code == 200
    assert response["Content-Type"] == f"image/{fmt}"
    colour = colour_at(response.content, pixel)
    assert near(colour, (*QUADRANTS[quadrant], 255)), colour
    assert "max-age=86400" in response["Cache-Control"]
    assert "private" in response["Cache-Control"]
    assert response["ETag"]


def test_outside_the_orthophoto_is_transparent_in_its_tiles_and_404_beyond(
    viewer_client, orthophoto
):
    beyond = quadrant_point("ne", offset_m=200)  # 72 m past the north-east corner
    # The widest zoom at which the corner's tile also covers the point beyond it.
    zoom = next(
        z
        for z in range(17, 10, -1)
        if tile_and_pixel(*beyond, z)[0] == tile_and_pixel(*quadrant_point("ne", 128), z)[0]
    )
    (z, x, y), pixel = tile_and_pixel(*beyond, zoom)
    response = viewer_client.get(tile_url(orthophoto, z, x, y))
    assert response.status_code == 200
    assert colour_at(response.content, pixel)[3] == 0
    (z, x, y), _ = tile_and_pixel(13.4, 52.5, 18)  # Berlin
    assert viewer_client.get(tile_url(orthophoto, z, x, y)).status_code == 404
    assert viewer_client.get(tile_url(orthophoto, 30, 0, 0)).status_code == 404
    assert viewer_client.get(f"/tiles/{orthophoto.key}/18/1/1.jpg").status_code == 404


def test_the_layer_reads_bounds_and_zooms_from_the_file(orthophoto):
    lon, lat = quadrant_point("nw", offset_m=10)
    assert orthophoto.kind == "raster"
    assert orthophoto.west < lon < orthophoto.east
    assert orthophoto.south < lat < orthophoto.north
    assert orthophoto.east - orthophoto.west < 0.01
    assert orthophoto.min_zoom == 0 and 19 <= orthophoto.max_zoom <= 24


@pytest.mark.parametrize("make", [make_mbtiles, make_pmtiles], ids=["mbtiles", "pmtiles"])
def test_archive_tiles_come_back_with_their_colours(viewer_client, media_root, tmp_path, make):
    tiles = archive_tiles()
    path = make(tmp_path / f"area.{make.__name__.removeprefix('make_')}", tiles)
    layer = layers.register_file(path, name="Area")
    assert layer.kind == make.__name__.removeprefix("make_")
    assert (layer.min_zoom, layer.max_zoom) == (12, 12)
    for (z, x, y), colour in tiles.items():
        for fmt in ("png", "webp"):
            response = viewer_client.get(tile_url(layer, z, x, y, fmt))
            assert response.status_code == 200, (z, x, y)
            assert near(colour_at(response.content, (128, 128)), (*colour, 255))
    (z, x, y) = min(tiles)
    assert viewer_client.get(tile_url(layer, z + 1, 2 * x, 2 * y)).status_code == 404
    assert viewer_client.get(tile_url(layer, z, x - 5, y)).status_code == 404


def test_only_signed_in_users_with_a_role_get_tiles(client, role_user, orthophoto):
    (z, x, y), _ = tile_and_pixel(*quadrant_point("sw"), 19)
    url = tile_url(orthophoto, z, x, y)
    assert client.get(url).status_code == 401
    client.force_login(role_user(None))
    assert client.get(url).status_code == 403
    client.force_login(role_user("viewer"))
    assert client.get(url).status_code == 200
    assert viewer_unknown_layer(client) == 404


def viewer_unknown_layer(client):
    return client.get("/tiles/no-such-layer/1/0/0.png").status_code
