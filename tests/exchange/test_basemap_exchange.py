"""Archives carry a reference to a test event's basemap; a backup carries the files."""

import zipfile

import pytest

from basemaps.models import BasemapLayer
from basemaps.selectors.layers import default_layer
from basemaps.services import layers
from exchange.archive import open_archive
from exchange.backup import make_backup
from exchange.export import export_events
from exchange.importer import ImportRefused, import_bundle
from tests.support.basemaps import quadrant_geotiff
from tests.support.field_day import field_day


def load(path):
    with open_archive(path) as bundle:
        return import_bundle(bundle)


def test_the_archive_names_the_events_basemap_and_the_import_links_it(
    db, tmp_path, media_root, settings
):
    settings.FTT_TILE_HOSTS = ["t.example"]
    event = field_day()
    ortho = layers.register_file(quadrant_geotiff(tmp_path / "o.tif"), name="Ortho", key="ortho")
    layers.set_event_default(event, ortho)
    export_events(tmp_path / "with-ortho.zip", [event])
    online = layers.register_url("https://t.example/{z}/{x}/{y}.png", name="Online", key="osm")
    layers.set_event_default(event, online)
    export_events(tmp_path / "with-url.zip", [event])
    with open_archive(tmp_path / "with-ortho.zip") as bundle:
        (record,) = list(bundle.records("basemaps"))
    assert (record["key"], record["kind"], record["name"]) == ("ortho", "raster", "Ortho")

    # An installation that has the orthophoto under the same key links it again.
    layers.set_event_default(event, None)
    plan = load(tmp_path / "with-ortho.zip")
    assert plan.counts["basemaps"]["added"] == 1
    assert default_layer(event.pk) == ortho
    assert load(tmp_path / "with-ortho.zip").counts["basemaps"]["unchanged"] == 1
    # An external layer travels whole: one that is missing is made again, but
    # off (no event starts on it, no report fetches from it) until an
    # administrator turns it on.
    online.delete()
    plan = load(tmp_path / "with-url.zip")
    assert plan.counts["basemaps"]["updated"] == 1
    made = BasemapLayer.objects.get(key="osm")
    assert (made.kind, made.url, made.enabled) == (
        "url",
        "https://t.example/{z}/{x}/{y}.png",
        False,
    )
    assert default_layer(event.pk) is None
    made.enabled = True
    made.save()
    assert default_layer(event.pk) == made
    assert BasemapLayer.objects.count() == 2


def test_an_archives_url_layer_to_a_host_nobody_allowed_is_refused(db, tmp_path, media_root):
    event = field_day()
    layer = BasemapLayer.objects.create(
        key="inside",
        name="Inside",
        kind=BasemapLayer.URL,
        url="http://127.0.0.1:8099/{z}/{x}/{y}.png",
    )
    layers.set_event_default(event, layer)
    export_events(tmp_path / "loopback.zip", [event])
    layer.delete()
    with pytest.raises(ImportRefused, match="127.0.0.1 is not among the tile servers"):
        load(tmp_path / "loopback.zip")
    assert not BasemapLayer.objects.filter(key="inside").exists()


@pytest.mark.django_db(transaction=True)
def test_a_backup_holds_the_basemap_files(tmp_path, media_root):
    tif = quadrant_geotiff(tmp_path / "ortho.tif")
    layer = layers.register_file(tif, name="Ortho")
    make_backup(tmp_path / "backup.zip")
    with zipfile.ZipFile(tmp_path / "backup.zip") as z:
        assert z.read(f"media/{layer.file.name}") == tif.read_bytes()
