"""The cockpit shows what the server stored: a fix without a position is not
drawn, a late batch is drawn where it was driven, and a page reloaded on a dead
link shows the state at the cut, with its age, never *live* before the server spoke."""

import uuid
from datetime import UTC, datetime, timedelta

import pytest
import requests
from playwright.sync_api import expect

from tests.e2e.test_cockpit_trust import row
from tests.support.browser import Robot, choose_event, login
from tests.support.screens import VIEWPORTS

pytestmark = pytest.mark.e2e

# Every Leaflet map the page makes, kept where a test can read its lines (an init
# script: the page's own modules keep them to themselves, and its CSP forbids eval).
KEEP_MAPS = """(() => {
  let leaflet;
  Object.defineProperty(window, "L", {
    configurable: true,
    get() { return leaflet; },
    set(value) {
      leaflet = value;
      if (value && value.Map && !window.__maps) {
        window.__maps = [];
        value.Map.addInitHook(function () { window.__maps.push(this); });
      }
    },
  });
})();"""

LINES = """() => {
  const map = window.__maps.find((m) => m.getContainer().id === "gps-map");
  const lines = [];
  map.eachLayer((layer) => {
    if (layer instanceof L.Polyline && !(layer instanceof L.Polygon)) lines.push(layer.getLatLngs().map((p) => [p.lat, p.lng]));
  });
  return lines;
}"""

TOKEN = """
from django.contrib.auth.models import User
from rest_framework.authtoken.models import Token
print(Token.objects.get_or_create(user=User.objects.get(username="otto"))[0].key)
"""


def drawn(page) -> list[list[list[float]]]:
    """The GPS map's lines, rounded as the server sends a track (1e-7 degrees)."""
    return [[[round(v, 7) for v in p] for p in line] for line in page.evaluate(LINES)]


def test_the_live_line_is_the_stored_line_with_a_no_fix_pose_and_a_late_batch(
    page, server, open_leg, shot
):
    token = server.python(TOKEN).strip().splitlines()[-1]
    api = requests.Session()
    api.headers["Authorization"] = f"Token {token}"
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
    finally:
        robot.stop()
    page.add_init_script(KEEP_MAPS)
    page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
    login(page, server, "otto")
    choose_event(page, open_leg)
    expect(page.locator("#live-status")).to_have_text("live")
    master = int(row(page, "#1").get_attribute("data-id"))
    t0 = datetime.now(UTC)

    def fix(i, lat_offset, seconds, **extra):
        return {
            "uid": str(uuid.uuid4()),
            "longitude": 7.1 + i * 1e-4,
            "latitude": 50.6 + lat_offset,
            "robot_stamp": (t0 + timedelta(seconds=seconds)).isoformat(),
            **extra,
        }

    def post(path, body):
        answer = api.post(f"{server.url}/api/{path}", json=body, timeout=30)
        assert answer.status_code == 201, answer.text

    gps = page.locator("#gps-map")
    # Live: a zigzag driven every two seconds (no three points in a line: the
    # server thins a track for the map, and keeps every corner).
    post("poses/batch/", {"segment": master, "poses": [fix(2 * i, (i % 2) * 1e-4, 2 * i) for i in range(5)]})
    expect(gps).to_have_attribute("data-track-points", "5")
    # A fix without a position (far off), then what the spool kept from between them.
    post("poses/", {"segment": master, **fix(9, 1e-3, 9, fix_status=-1)})
    post("poses/batch/", {"segment": master, "poses": [fix(2 * i + 1, -3e-5, 2 * i + 1) for i in range(2)]})
    expect(gps).to_have_attribute("data-track-points", "7")
    live = drawn(page)
    shot(page, "tablet-live-line")
    page.reload()
    expect(page.locator("#live-status")).to_have_text("live")
    expect(gps).to_have_attribute("data-track-points", "7")
    assert drawn(page) == live
    # Driving order: west to east, the late points between their neighbours.
    (line,) = live
    assert [p[1] for p in line] == sorted(p[1] for p in line)
