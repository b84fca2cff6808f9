"""The whole field test as a new user does it, in a real browser: the walk of
the original's manual (§3.1-3.8) on the tablet held in one hand, with Cancel
in every dialog, a reload while logging, and End right after Stop."""

import io
import time

import pytest
from PIL import Image as PILImage
from playwright.sync_api import expect

from tests.support.browser import Robot, end_level, login
from tests.support.screens import VIEWPORTS

pytestmark = pytest.mark.e2e

NOTE = "Grüße aus Köln: Weg überflutet, Ölspur – 東京 ✓"


SEEN_TOASTS = """() => {
  const box = document.querySelector("#notice");
  new MutationObserver(() => {
    if (box.textContent.includes("Ended test event")) document.body.dataset.sawEnded = "yes";
  }).observe(box, { childList: true, characterData: true, subtree: true });
}"""


def photo_bytes() -> bytes:
    buffer = io.BytesIO()
    PILImage.new("RGB", (64, 48), (200, 120, 40)).save(buffer, "JPEG")
    return buffer.getvalue()


def admin_adds(page, model, values, shot, name):
    page.goto(page.url.split("/admin/")[0] + f"/admin/events/{model}/add/")
    for field, value in values.items():
        page.fill(f"#id_{field}", value)
    page.click("input[name=_save]")
    expect(page.locator(".messagelist")).to_contain_text("added successfully")
    shot(page, name)


def new_level(page, level, values, shot):
    """Press New on a level and save its edit dialog; a tuple value picks an option."""
    page.locator(f'[data-action="new"][data-level="{level}"]').click()
    dialog = page.locator("#form-dialog")
    expect(dialog).to_be_visible()
    for label, value in values.items():
        if isinstance(value, tuple):
            dialog.get_by_label(label).select_option(label=value[0])
        else:
            dialog.get_by_label(label).fill(value)
    shot(page, f"{level}-dialog")
    dialog.get_by_role("button", name="Save").click()
    expect(dialog).to_be_hidden()


def cancel_new(page, level, values):
    """Press New, type into the dialog, Cancel: no entry appears."""
    options = page.locator(f"#pick-{level} option")
    expect(options.first).to_be_attached()  # the picker has loaded (a placeholder at least)
    before = options.count()
    page.locator(f'[data-action="new"][data-level="{level}"]').click()
    dialog = page.locator("#form-dialog")
    expect(dialog).to_be_visible()
    for label, value in values.items():
        dialog.get_by_label(label).fill(value)
    dialog.get_by_role("button", name="Cancel").click()
    expect(dialog).to_be_hidden()
    page.wait_for_timeout(300)  # a write would have answered by now
    expect(options).to_have_count(before)


def cancel_edit(page, level, label, value):
    """Open Edit, change a field, Cancel: the entry keeps its value."""
    edit = page.locator(f'[data-action="edit"][data-level="{level}"]')
    dialog = page.locator("#form-dialog")
    edit.click()
    field = dialog.get_by_label(label)
    kept = field.input_value()
    field.fill(value)
    dialog.get_by_role("button", name="Cancel").click()
    expect(dialog).to_be_hidden()
    edit.click()
    expect(dialog.get_by_label(label)).to_have_value(kept)
    dialog.get_by_role("button", name="Cancel").click()
    expect(dialog).to_be_hidden()


def selection(page):
    return [page.locator(f"#pick-{level}").input_value() for level in ("event", "shift", "leg")]


def wait_live(locator, committed_at, figures, label):
    # Appearing without a reload is asserted here; how fast is a figure for
    # benchmarks/live_latency.py, which the printed delays can be compared with.
    expect(locator).to_be_visible(timeout=3000)
    figures[label] = time.time() - committed_at


def test_field_walk(browser, server, shot):
    figures = {}
    # 1. The administrator configures what a shift needs.
    admin = browser.new_page()
    login(admin, server, "ada")
    expect(admin.locator("#first-run")).to_contain_text("Add a vehicle")
    shot(admin, "admin-first-run-hint")
    base = server.url
    admin.goto(f"{base}/admin/")
    admin_adds(admin, "performer", {"institution": "Fraunhofer FKIE"}, shot, "performer")
    admin_adds(
        admin, "vehicle", {"key": "husky-walk", "short_description": "Husky Walk"}, shot, "vehicle"
    )
    admin_adds(
        admin, "posesource", {"key": "rtk", "short_description": "RTK GNSS"}, shot, "pose-source"
    )
    admin.goto(base + "/")
    expect(admin.locator("#first-run")).to_have_count(0)
    admin.close()

    robot = Robot(server, "husky-walk")
    try:
        page = browser.new_page(**VIEWPORTS["tablet"])
        page.route("**/tiles/**", lambda r: r.fulfill(status=404))
        login(page, server, "otto")
        expect(page.locator("#live-status")).to_have_text("live")

        # 2. The operator opens a test event, a shift and a leg; Cancel leaves none behind.
        cancel_new(page, "event", {"Location": "Versehentlich"})
        new_level(
            page, "event", {"Location": "Köln-Wahn Übungsplatz", "Time zone": "Europe/Berlin"}, shot
        )
        expect(page.locator("#pick-event option:checked")).to_contain_text("Köln-Wahn Übungsplatz")
        cancel_new(page, "shift", {"Test intent": "Versehentlich"})
        new_level(page, "shift", {"Vehicle": ("Husky Walk",), "Test intent": "Überlandfahrt"}, shot)
        expect(page.locator("#pick-shift option:checked")).to_contain_text("Husky Walk")
        cancel_new(page, "leg", {"Note": "Versehentlich"})
        new_level(page, "leg", {}, shot)
        expect(page.locator("#segments-section")).to_be_visible()
        expect(page.locator("#segments-empty")).to_be_visible()
        shot(page, "leg-open")

        # 3. Logging starts; the robot's segments appear without a reload.
        toggle = page.locator("#logging-toggle")
        expect(toggle).to_be_enabled(timeout=8000)
        expect(page.locator("#collector-status")).to_contain_text("online")
        toggle.click()
        expect(toggle).to_have_text("Stop logging", timeout=5000)

        rows = page.locator("#segment-table tbody tr")
        at = robot.do("auto")
        wait_live(rows.filter(has_text="AUTO"), at, figures, "AUTO segment")
        at = robot.do("poses")
        expect(page.locator("#gps-map")).to_have_attribute("data-tracks", "1", timeout=3000)
        figures["poses"] = time.time() - at
        at = robot.do("ito")
        ito_row = rows.filter(has_text="ITO")
        wait_live(ito_row, at, figures, "ITO segment")
        expect(page.locator("#gps-map")).to_have_attribute("data-take-overs", "1")
        shot(page, "live-segments")

        # A reload while logging brings back the same leg, still logging.
        chosen = selection(page)
        page.reload()
        expect(page.locator("#pick-leg")).to_have_value(chosen[2])
        assert selection(page) == chosen
        expect(toggle).to_have_text("Stop logging")
        expect(ito_row).to_be_visible()
        expect(page.locator("#mode-name")).to_have_text("ITO")
        shot(page, "reloaded-while-logging")

        # 4. A quick reason, a note with umlauts and a photo.
        ito_row.click()
        page.get_by_role("button", name="Safety", exact=True).click()
        expect(ito_row.locator("td").nth(2)).to_have_text("Safety")
        shot(page, "quick-reason")

        ito_row.dblclick()
        seg = page.locator("#segment-dialog")
        expect(seg).to_be_visible()
        seg.get_by_label("New note").fill(NOTE)
        seg.get_by_role("button", name="Add note").click()
        note = seg.locator(".notes li").filter(has_text=NOTE)
        expect(note).to_be_visible()
        expect(note).to_contain_text("Jörg Müller")
        seg.locator("input[name=file]").set_input_files(
            {"name": "pothole.jpg", "mimeType": "image/jpeg", "buffer": photo_bytes()}
        )
        expect(seg.locator(".images img")).to_have_count(1)
        expect(seg.locator(".images img")).to_have_js_property("complete", True)
        shot(page, "segment-dialog")
        # Editing a note and cancelling keeps the note as it was.
        note.get_by_role("button", name="Edit").click()
        seg.get_by_label("Note text").fill("Verworfen")
        seg.get_by_role("button", name="Cancel").click()
        expect(seg.locator(".notes li .text")).to_have_text(NOTE)
        seg.get_by_role("button", name="Close").last.click()
        expect(seg).to_be_hidden()

        # Cancel in the other dialogs changes nothing: Edit, Delete, map settings.
        cancel_edit(page, "shift", "Test intent", "Versehentlich geändert")
        page.locator('[data-action="delete"][data-level="leg"]').click()
        confirm = page.locator("#confirm-dialog")
        confirm.get_by_role("button", name="Keep it").click()
        expect(confirm).to_be_hidden()
        expect(page.locator("#pick-leg option:checked")).to_contain_text("Leg 1")
        expect(ito_row).to_be_visible()
        page.locator("#open-map-settings").click()
        settings = page.locator("#map-settings-dialog")
        settings.get_by_label("Tile URL").fill("http://127.0.0.1:9/verworfen/{z}/{x}/{y}.png")
        settings.get_by_role("button", name="Cancel").click()
        expect(settings).to_be_hidden()
        assert page.evaluate("localStorage.getItem('ftt.tileUrl')") is None

        # 5. Logging stops and the test event is ended at once, without waiting
        #    for the robot to confirm the stop: both go through.
        # The robot's answer to the stop may replace the toast of the end: every
        # toast shown is watched to see that the end's was one of them.
        page.evaluate(SEEN_TOASTS)
        toggle.click()
        end_level(page, "event")
        expect(page.locator('[data-state="event"]')).to_have_text("closed")
        expect(page.locator("body")).to_have_attribute("data-saw-ended", "yes")
        expect(page.locator("#error")).to_be_hidden()
        expect(toggle).to_have_text("Start logging", timeout=5000)
        expect(ito_row.locator("td").nth(7)).to_have_text("closed", timeout=3000)
        expect(page.locator('[data-action="reopen"][data-level="event"]')).to_be_visible()
        shot(page, "test-event-ended")

        # What the page showed survives a reload, Unicode included.
        page.reload()
        expect(page.locator("#pick-event option:checked")).to_contain_text("Köln-Wahn Übungsplatz")
        assert selection(page)[0] != ""

        # 8. Deleting: "Keep it" keeps the test event, Delete removes it with all below.
        events = page.locator("#pick-event option")
        count = events.count()
        page.locator('[data-action="delete"][data-level="event"]').click()
        confirm.get_by_role("button", name="Keep it").click()
        expect(events).to_have_count(count)
        page.locator('[data-action="delete"][data-level="event"]').click()
        expect(confirm).to_contain_text("with all its shifts, legs, segments")
        confirm.get_by_role("button", name="Delete").click()
        expect(page.locator("#notice")).to_contain_text("Deleted test event")
        expect(page.locator("#pick-event option").filter(has_text="Köln-Wahn")).to_have_count(0)
        shot(page, "test-event-deleted")
        print("live delays (s):", {k: round(v, 3) for k, v in figures.items()})
    finally:
        robot.stop()
