"""Nothing typed on a dead link is lost: quick reasons, notes and photos made
while the server cannot be reached wait in the browser, survive a reload on the
dead link (the service worker keeps the cockpit), and are stored exactly once
when the link returns.  The robot's marker shows where it is, greyed when the
page has heard no fix for a few seconds."""

import io
import re

import pytest
from PIL import Image
from playwright.sync_api import expect

from tests.e2e.test_cockpit_trust import row
from tests.support.browser import Robot, choose_event, login
from tests.support.screens import VIEWPORTS

pytestmark = pytest.mark.e2e


# Resolves once the service worker controls the page (a function: the page's CSP forbids eval).
CONTROLLED = """async () => {
  const sw = navigator.serviceWorker;
  await sw.ready;
  if (sw.controller) return;
  await new Promise((done) => sw.addEventListener("controllerchange", done, { once: true }));
}"""


def png() -> bytes:
    buffer = io.BytesIO()
    Image.new("RGB", (8, 8), (200, 40, 40)).save(buffer, format="PNG")
    return buffer.getvalue()


def test_writes_made_during_a_cut_are_stored_once_after_it_and_survive_a_reload(
    page, server, link, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("ito")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        login(page, link, "otto")
        # The service worker takes the page over; from then on it keeps what the page reads.
        page.evaluate(CONTROLLED)
        choose_event(page, open_leg)
        badge, waiting = page.locator("#live-status"), page.locator("#outbox")
        expect(badge).to_have_text("live")
        expect(page.locator("#quick-target")).to_have_text("Reason for #1.1:")
        robot.do("poses")
        gps, local = page.locator("#gps-map"), page.locator("#local-map")
        expect(gps).to_have_attribute("data-robot", "fresh")
        expect(local).to_have_attribute("data-robot", "fresh")
        # The local map knows the heading: its marker carries the arrow.
        expect(local.locator(".robot-marker .robot-heading")).to_have_count(1)
        page.locator("#show-local").check()
        shot(page, "tablet-robot-marker")

        link.cut()
        expect(badge).not_to_have_text("live", timeout=5000)
        page.get_by_role("button", name="Safety", exact=True).click()
        expect(waiting).to_have_text("1 waiting to send")
        row(page, "#1.1").click()
        page.locator("#segment-edit").click()
        dialog = page.locator("#segment-dialog")
        expect(dialog.locator(".dialog-error")).to_contain_text("cannot be reached")
        dialog.locator("textarea[name=text]").fill("Wet grass at the gate")
        dialog.get_by_role("button", name="Add note").click()
        expect(waiting).to_have_text("2 waiting to send")
        dialog.locator("input[name=file]").set_input_files(
            files=[{"name": "gate.png", "mimeType": "image/png", "buffer": png()}]
        )
        expect(waiting).to_have_text("3 waiting to send")
        dialog.get_by_role("button", name="Close").click()
        # No fix heard for a few seconds: the marker is greyed.
        expect(gps).to_have_attribute("data-robot", "stale", timeout=8000)
        for screen, options in VIEWPORTS.items():
            page.set_viewport_size(options["viewport"])
            expect(waiting).to_be_in_viewport()
            shot(page, f"{screen}-offline-waiting")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])

        # Reloaded on the dead link: the cockpit opens with its last state and its queue.
        page.reload()
        expect(page.locator("#mode-name")).to_have_text(
            re.compile(r"^last known: ITO, \d+ s ago$"), timeout=15_000
        )
        expect(row(page, "#1.1")).to_be_visible()
        expect(waiting).to_have_text("3 waiting to send")
        # What the robot does now cannot be known offline: no kept "online".
        expect(page.locator("#collector-status")).not_to_contain_text("online")
        shot(page, "tablet-reloaded-offline")

        link.restore()
        expect(badge).to_have_text("live", timeout=10_000)
        expect(waiting).to_be_hidden(timeout=5000)
    finally:
        robot.stop()
    expect(row(page, "#1.1").locator("td").nth(2)).to_have_text("Safety")
    # What the server stored: each write once.
    take_over = row(page, "#1.1").get_attribute("data-id")
    master = page.request.get(f"{link.url}/api/segments/{take_over}/").json()["parent"]
    notes = page.request.get(f"{link.url}/api/notes/?segment={take_over}").json()["results"]
    images = page.request.get(f"{link.url}/api/images/?segment={master}").json()["results"]
    assert [n["text"] for n in notes] == ["Wet grass at the gate"]
    assert len(images) == 1
