"""With the internet unplugged, the operator sees the event's orthophoto under the robot's track."""

import io
import re
import textwrap
import time

import numpy as np
import pytest
from PIL import Image
from playwright.sync_api import expect

from tests.support.basemaps import QUADRANTS
from tests.support.browser import Robot, login, open_leg_code

pytestmark = pytest.mark.e2e

# The simulated robot drives from here 0.0005° east and 0.00025° north.
TRACK_MIDDLE = (7.10025, 50.600125)


@pytest.fixture
def leg_on_orthophoto(server, tmp_path):
    key = f"ortho-{int(time.time() * 1000) % 1000000}"
    server.python(
        open_leg_code(key)
        + textwrap.dedent(
            f"""
        from pathlib import Path
        from basemaps.services import layers
        from tests.support.basemaps import quadrant_geotiff
        tif = quadrant_geotiff(Path({str(tmp_path)!r}) / "ortho.tif", pixel_m=0.25,
                               centre={TRACK_MIDDLE!r})
        layer = layers.register_file(tif, name="Orthophoto {key}", key="{key}")
        layers.set_event_default(e, layer)
        """
        )
    )
    robot = Robot(server, key)
    try:
        robot.do("auto")
        robot.do("poses")
    finally:
        robot.stop()
    return key


def share_near(image: np.ndarray, colour, tolerance=16) -> float:
    return float((np.abs(image - colour).max(axis=2) <= tolerance).mean())


def test_the_orthophoto_shows_under_the_track_with_no_internet(
    page, server, leg_on_orthophoto, shot
):
    outside = []

    def only_ftt(route):
        if route.request.url.startswith(server.url):
            route.continue_()
        else:
            outside.append(route.request.url)
            route.abort()

    page.route("**/*", only_ftt)
    login(page, server, "otto")
    option = page.locator("#pick-event option", has_text=f"Gelände {leg_on_orthophoto}")
    page.select_option("#pick-event", value=option.get_attribute("value"))
    gps = page.locator("#gps-map")
    own = gps.locator(f"img.leaflet-tile-loaded[src*='/tiles/{leg_on_orthophoto}/']")
    expect(own.first).to_be_attached()
    expect(gps).to_have_attribute("data-tracks", re.compile(r"^[1-9]"))
    expect(page.locator("#tile-message")).to_be_hidden()
    # The switcher offers the orthophoto (chosen) and the site's tile server.
    switcher = gps.locator(".leaflet-control-layers-base")
    expect(switcher.locator("label", has_text="Orthophoto")).to_have_count(1)
    expect(switcher.locator("label", has_text="Tile server")).to_have_count(1)
    page.wait_for_function(
        "[...document.querySelectorAll('#gps-map img.leaflet-tile')].every(i => i.complete)"
    )
    shot(page, "orthophoto")

    picture = np.asarray(Image.open(io.BytesIO(gps.screenshot())).convert("RGB")).astype(int)
    for name, colour in QUADRANTS.items():
        assert share_near(picture, colour) > 0.05, name
    assert share_near(picture, (0x1A, 0x9C, 0x3A), tolerance=30) > 0.001  # the AUTO track
    # Blocked were only the site's (unplugged) tile server's tiles, asked before the
    # event's default basemap replaced it.
    assert all(url.startswith("http://127.0.0.1:9/") for url in outside), outside

    # Opened on this event, the cockpit asks the internet for nothing.
    outside.clear()
    page.reload()
    expect(own.first).to_be_attached()
    page.wait_for_load_state("networkidle")
    assert outside == []

    # The fleet, with this robot logging, starts on the event's orthophoto too.
    server.python(
        f"""
        from events.models import Leg
        from rosbridge_app.services import collectors
        leg = Leg.objects.get(shift__vehicle__key="{leg_on_orthophoto}")
        vehicle = leg.shift.vehicle
        collectors.heartbeat(vehicle.key, vehicle=vehicle, logging=True, leg=leg)
        """
    )
    page.goto(f"{server.url}/?view=fleet")
    fleet = page.locator("#fleet-map")
    expect(
        fleet.locator(f"img.leaflet-tile-loaded[src*='/tiles/{leg_on_orthophoto}/']").first
    ).to_be_attached()
    expect(
        fleet.locator(".leaflet-control-layers-base label", has_text="Orthophoto")
    ).to_have_count(1)
    page.wait_for_load_state("networkidle")
    assert outside == []
    shot(page, "fleet-on-orthophoto")
