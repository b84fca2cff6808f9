"""The GUI's layer switcher is filled from the server: every layer, the event's default marked."""

from basemaps.services import layers
from tests.support.basemaps import quadrant_geotiff

URL = "/gui/api/basemaps/"


def test_the_switcher_lists_every_layer_and_marks_the_events_default(
    client, role_user, test_event, media_root, tmp_path, settings
):
    settings.FTT_TILE_HOSTS = ["t.example"]
    ortho = layers.register_file(quadrant_geotiff(tmp_path / "o.tif"), name="Ortho", key="ortho")
    layers.register_url("https://t.example/{z}/{x}/{y}.png", name="Online", attribution="© T")
    layers.set_event_default(test_event, ortho)
    client.force_login(role_user("viewer"))

    rows = {row["name"]: row for row in client.get(URL, {"event": test_event.pk}).json()["layers"]}

    assert rows["Ortho"]["url"] == "/tiles/ortho/{z}/{x}/{y}.png"
    assert rows["Ortho"]["default"] and not rows["Online"]["default"]
    (south, west), (north, east) = rows["Ortho"]["bounds"]
    assert west < 7.12 < east and south < 50.61 < north
    assert rows["Online"] | {"default": None} == {
        "key": "online",
        "name": "Online",
        "url": "https://t.example/{z}/{x}/{y}.png",
        "attribution": "© T",
        "minZoom": 0,
        "maxZoom": 19,
        "bounds": None,
        "default": None,
    }
    others = client.get(URL).json()["layers"]
    assert [row["default"] for row in others] == [False, False]


def test_an_attribution_is_text_not_html(client, role_user, media_root, tmp_path):
    hostile = '<img src=x onerror="alert(1)"> <a href="https://evil.example">x</a>'
    layers.register_file(quadrant_geotiff(tmp_path / "o.tif"), name="Ortho", attribution=hostile)
    client.force_login(role_user("viewer"))
    (row,) = client.get(URL).json()["layers"]
    assert row["attribution"] == (
        "&lt;img src=x onerror=&quot;alert(1)&quot;&gt; "
        "&lt;a href=&quot;https://evil.example&quot;&gt;x&lt;/a&gt;"
    )


def test_the_layer_list_needs_a_role_and_a_proper_event(client, role_user, db):
    assert client.get(URL).status_code in (401, 403)
    client.force_login(role_user("viewer"))
    response = client.get(URL, {"event": "x"})
    assert response.status_code == 400
    assert "event" in str(response.json())
