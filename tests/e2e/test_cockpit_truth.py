"""The cockpit shows what the server stored: a fix without a position is not
drawn, a late batch is drawn where it was driven, and a page reloaded on a dead
link shows the state at the cut, with its age, never *live* before the server spoke."""

import re
import uuid
from datetime import UTC, datetime, timedelta

import pytest
import requests
from playwright.sync_api import expect

from tests.e2e.test_cockpit_trust import row
from tests.support.browser import Robot, choose_event, login
from tests.support.screens import VIEWPORTS

# The badge may first say stale when a heartbeat comes late on a busy machine.
LIVE = 15_000

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
    if (!(layer instanceof L.Polyline) || layer instanceof L.Polygon) return;
    lines.push(layer.getLatLngs().map((p) => [p.lat, p.lng]));
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
    expect(page.locator("#live-status")).to_have_text("live", timeout=LIVE)
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
    post(
        "poses/batch/",
        {"segment": master, "poses": [fix(2 * i, (i % 2) * 1e-4, 2 * i) for i in range(5)]},
    )
    expect(gps).to_have_attribute("data-track-points", "5")
    # A fix without a position (far off), then what the spool kept from between them.
    post("poses/", {"segment": master, **fix(9, 1e-3, 9, fix_status=-1)})
    post(
        "poses/batch/",
        {"segment": master, "poses": [fix(2 * i + 1, -3e-5, 2 * i + 1) for i in range(2)]},
    )
    expect(gps).to_have_attribute("data-track-points", "7")
    live = drawn(page)
    shot(page, "tablet-live-line")
    page.reload()
    expect(page.locator("#live-status")).to_have_text("live", timeout=LIVE)
    expect(gps).to_have_attribute("data-track-points", "7")
    assert drawn(page) == live
    # Driving order: west to east, the late points between their neighbours.
    (line,) = live
    assert [p[1] for p in line] == sorted(p[1] for p in line)


# Resolves once the service worker controls the page (a function: the page's CSP forbids eval).
CONTROLLED = """async () => {
  const sw = navigator.serviceWorker;
  await sw.ready;
  if (sw.controller) return;
  await new Promise((done) => sw.addEventListener("controllerchange", done, { once: true }));
}"""


def never_live_until(page, done):
    """Fails if the badge says *live* before ``done()`` holds (checked every 100 ms;
    a reload on a stalled link waits for the service worker's 4 s first)."""
    badge = page.locator("#live-status")
    deadline = 300
    while not done():
        assert badge.text_content() != "live", "live before the server answered"
        deadline -= 1
        assert deadline, "the page never showed its last known state"
        page.wait_for_timeout(100)


def test_a_reload_after_a_stall_and_a_cut_shows_the_state_at_the_cut(
    page, server, link, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        login(page, link, "otto")
        page.evaluate(CONTROLLED)
        choose_event(page, open_leg)
        badge, mode = page.locator("#live-status"), page.locator("#mode-name")
        expect(badge).to_have_text("live", timeout=LIVE)
        expect(mode).to_have_text("AUTO")
        # Live, after the page was loaded: a take-over (#2), its end and a second one (#4).
        robot.do("ito")
        robot.do("auto")
        robot.do("ito")
        expect(mode).to_have_text("ITO")
        expect(row(page, "#4.1")).to_be_visible()
        link.stall()
        expect(badge).to_have_text("stale", timeout=6000)
        expect(mode).to_have_text(re.compile(r"^last known: ITO, \d+ s ago$"))
        for screen, options in VIEWPORTS.items():
            page.set_viewport_size(options["viewport"])
            shot(page, f"{screen}-stale-after-stall")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        # Reloaded on the stalled link, then on a cut one: each time the state at
        # the cut, with its age, and never *live*.
        for _link in ("stalled", "cut"):
            page.reload(wait_until="commit")
            never_live_until(
                page, lambda: re.match(r"^last known: ITO, \d+ s ago$", mode.text_content() or "")
            )
            expect(row(page, "#4.1")).to_be_visible()
            expect(row(page, "#2.1")).to_be_visible()
            expect(page.locator("#error")).to_be_hidden()
            link.cut()
        for screen, options in VIEWPORTS.items():
            page.set_viewport_size(options["viewport"])
            shot(page, f"{screen}-reloaded-while-cut")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        robot.do("auto")
        link.restore()
        # Live only with what the server says now: AUTO, the moment the badge says so.
        expect(badge).to_have_text("live", timeout=15_000)
        assert mode.text_content() == "AUTO"
    finally:
        robot.stop()


def test_a_cockpit_reloaded_from_the_kept_fleet_page_shows_the_legs_history(
    page, server, link, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("ito")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        login(page, link, "otto")
        page.evaluate(CONTROLLED)
        choose_event(page, open_leg)
        cockpit = page.url
        expect(page.locator("#live-status")).to_have_text("live", timeout=LIVE)
        expect(row(page, "#1.1")).to_be_visible()
        # Live, after the page was loaded: the take-over ends, a second one starts.
        robot.do("auto")
        robot.do("ito")
        expect(row(page, "#3.1")).to_be_visible()
        # The last page loaded, and so kept, is the fleet's.
        page.goto(f"{link.url}/?view=fleet")
        expect(page.locator("#fleet-view")).to_be_visible()
        expect(page.locator("#live-status")).to_have_text("live", timeout=LIVE)
        link.cut()
        page.goto(cockpit, wait_until="commit")
        mode = page.locator("#mode-name")
        never_live_until(
            page, lambda: re.match(r"^last known: ITO, \d+ s ago$", mode.text_content() or "")
        )
        expect(row(page, "#3.1")).to_be_visible()
        expect(row(page, "#1.1")).to_be_visible()
        expect(page.locator("#error")).to_be_hidden()
        expect(page.locator("#live-status")).not_to_have_text("live")
        shot(page, "tablet-fleet-copy-reloaded-while-cut")
    finally:
        robot.stop()
