"""ftt_basemap fetch against a tile server on loopback, and ftt_basemap import."""

import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest
from django.core.management import CommandError, call_command

from basemaps.files import inspect_file
from basemaps.models import BasemapLayer
from basemaps.selectors.layers import default_layer
from basemaps.selectors.tiles import render_tile
from basemaps.services import fetching, layers
from tests.support.basemaps import colour_at, near, quadrant_geotiff, solid_png

BBOX = (7.115, 50.608, 7.125, 50.612)


def tile_colour(z, x, y):
    return (x * 37 % 256, y * 53 % 256, z * 10)


class TileServer:
    """Serves a solid PNG per tile; can refuse once with 429 or break after some tiles."""

    def __init__(self):
        self.requests: list[tuple[str, str]] = []
        self.fail_after: int | None = None
        self.busy_once = False
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802 - http.server's name
                server.requests.append((self.path, self.headers.get("User-Agent", "")))
                if server.busy_once:
                    server.busy_once = False
                    self.send_response(429)
                    self.send_header("Retry-After", "0")
                    self.end_headers()
                    return
                served = len(server.requests) - 1
                if server.fail_after is not None and served >= server.fail_after:
                    self.send_response(500)
                    self.end_headers()
                    return
                z, x, y = (int(v) for v in self.path.strip("/").removesuffix(".png").split("/"))
                body = solid_png(tile_colour(z, x, y))
                self.send_response(200)
                self.send_header("Content-Type", "image/png")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args):
                pass

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_port}/{{z}}/{{x}}/{{y}}.png"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def tile_server():
    server = TileServer()
    yield server
    server.close()


def fetch(server, out, *extra):
    args = ["fetch", "--bbox", ",".join(map(str, BBOX)), "--zooms", "15-16"]
    call_command("ftt_basemap", *args, "--from", server.url, str(out), "--rate", "500", *extra)


def expected_tiles():
    return fetching.area_tiles(BBOX, [15, 16])


@pytest.mark.parametrize("suffix", ["pmtiles", "mbtiles"])
def test_fetch_writes_an_archive_ftt_serves_with_the_servers_tiles(
    db, tile_server, media_root, tmp_path, suffix
):
    out = tmp_path / f"field.{suffix}"
    fetch(tile_server, out, "--register", "--name", "Field OSM", "--attribution", "© OSM")
    tiles = expected_tiles()
    assert len(tile_server.requests) == len(tiles) > 4
    assert all("FTT" in agent for _, agent in tile_server.requests)
    facts = inspect_file(out)
    assert (facts.kind, facts.min_zoom, facts.max_zoom) == (suffix, 15, 16)
    layer = BasemapLayer.objects.get(name="Field OSM")
    assert layer.attribution == "© OSM"
    for tile in tiles:
        data = render_tile(layer, tile.z, tile.x, tile.y)
        assert near(colour_at(data, (10, 10)), (*tile_colour(tile.z, tile.x, tile.y), 255))
    assert not list(tmp_path.glob("*.part*"))


def test_an_interrupted_fetch_resumes_without_asking_again(tile_server, tmp_path, capsys):
    out = tmp_path / "field.pmtiles"
    tile_server.fail_after = 3
    with pytest.raises(CommandError, match="run the same command again"):
        fetch(tile_server, out, "--retries", "0")
    assert not out.exists()
    first = [path for path, _ in tile_server.requests[:3]]
    tile_server.fail_after = None
    tile_server.requests.clear()
    tile_server.busy_once = True  # and the server asks to slow down once
    fetch(tile_server, out)
    asked = [path for path, _ in tile_server.requests]
    total = len(expected_tiles())
    assert len(asked) == total - 3 + 1  # the refused request is asked again
    assert not set(first) & set(asked)
    said = capsys.readouterr().out
    assert f"{total} tiles, {total - 3} downloaded, 3 from an earlier run" in said
    assert inspect_file(out).kind == "pmtiles"


def test_fetch_refuses_a_bulk_download(tile_server, tmp_path):
    with pytest.raises(CommandError, match="forbid bulk downloads"):
        fetch(tile_server, tmp_path / "x.mbtiles", "--max-tiles", "3")
    assert tile_server.requests == []


def test_import_registers_a_geotiff_as_the_default_of_an_event(test_event, media_root, tmp_path):
    tif = quadrant_geotiff(tmp_path / "ortho.tif")
    call_command("ftt_basemap", "import", str(tif), "--name", "Ortho", "--event", test_event.pk)
    layer = default_layer(test_event.pk)
    assert (layer.name, layer.kind) == ("Ortho", "raster")


def test_import_of_a_bad_file_says_why_and_keeps_nothing(db, media_root, tmp_path):
    bad = tmp_path / "notes.tif"
    bad.write_text("not an image")
    with pytest.raises(CommandError, match="Not a georeferenced raster"):
        call_command("ftt_basemap", "import", str(bad))
    assert not BasemapLayer.objects.exists()
    assert not (media_root / "basemaps").exists() or not any((media_root / "basemaps").iterdir())


def test_the_event_default_can_be_changed_and_cleared(test_event, media_root, tmp_path, settings):
    settings.FTT_TILE_HOSTS = ["t.example"]
    layer = layers.register_url("https://t.example/{z}/{x}/{y}.png", name="OSM")
    layers.set_event_default(test_event, layer)
    assert default_layer(test_event.pk) == layer
    layers.set_event_default(test_event, None)
    assert default_layer(test_event.pk) is None
