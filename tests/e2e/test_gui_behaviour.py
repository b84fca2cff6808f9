"""Roles, maps without tiles, reconnects, notes and error messages in the browser."""

import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import Robot, choose_event, end_level, login
from tests.support.pdf import flat, pdf_text

pytestmark = pytest.mark.e2e

choose = choose_event


def test_viewer_sees_but_cannot_change_anything(page, server, open_leg, shot):
    login(page, server, "vera")
    choose(page, open_leg)
    for action in ("new", "end", "delete"):
        expect(page.locator(f'[data-action="{action}"][data-level="leg"]')).to_be_disabled()
    expect(page.get_by_role("button", name="Safety", exact=True)).to_be_disabled()
    expect(page.locator("#segment-new")).to_be_disabled()
    # Viewers read every field of a level, but cannot save it.
    page.locator('[data-action="edit"][data-level="event"]').click()
    form = page.locator("#form-dialog")
    expect(form.get_by_label("Location")).to_have_value(f"Gelände {open_leg}")
    expect(form.get_by_label("Location")).to_be_disabled()
    expect(form.get_by_role("button", name="Save")).to_be_hidden()
    form.get_by_role("button", name="Cancel").click()
    shot(page, "viewer")
    # Even a request made by hand is refused, and the page says why in words.
    page.evaluate(
        "document.querySelector('#segment-new').disabled = false;"
        "document.querySelector('#segment-new').click()"
    )
    expect(page.locator("#error")).to_contain_text("does not have the role")
    expect(page.locator("#segment-table tbody tr")).to_have_count(0)


def test_map_without_tiles_says_so_and_still_draws(page, server, open_leg, shot):
    # The loopback tile address in the server's settings has nothing listening.
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
        robot.do("poses")
    finally:
        robot.stop()
    login(page, server, "otto")
    choose(page, open_leg)
    expect(page.locator("#tile-message")).to_contain_text("tiles are unavailable")
    expect(page.locator("#gps-map")).to_have_class(re.compile(r"(^|\s)no-tiles(\s|$)"))
    # The track is drawn on the map's canvas, which tells what it holds.
    expect(page.locator("#gps-map")).to_have_attribute("data-tracks", "1")
    expect(page.locator("#gps-map canvas")).to_be_visible()
    shot(page, "no-tiles")


def test_reconnecting_browser_catches_up(page, server, link, open_leg, shot):
    login(page, link, "otto")
    choose(page, open_leg)
    expect(page.locator("#live-status")).to_have_text("live")
    # The link drops and stays down for a while, as a flaky field network does.
    link.cut()
    expect(page.locator("#live-status")).to_have_text("reconnecting…")
    # What the page shows is marked as the last known state, not as live.
    expect(page.locator("#mode-name")).to_contain_text("last known: no open segment", timeout=5000)
    robot = Robot(server, open_leg)
    try:
        robot.do("ito")
    finally:
        robot.stop()
    rows = page.locator("#segment-table tbody tr")
    expect(rows).to_have_count(0)
    link.restore()
    expect(page.locator("#live-status")).to_have_text("live", timeout=6000)
    expect(rows.filter(has_text="ITO")).to_have_count(1, timeout=3000)
    shot(page, "caught-up")


def test_new_take_over_and_end_show_every_changed_row_without_reading_the_list(
    page, server, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
    finally:
        robot.stop()
    # The change feed stays away (the page's websocket reaches no server): only
    # the writes' answers can change the list.
    page.route_web_socket(re.compile(r"/ws/live/"), lambda socket: None)
    login(page, server, "otto")
    choose(page, open_leg)
    rows = page.locator("#segment-table tbody tr")
    expect(rows).to_have_count(1)
    reads = []
    page.on("request", lambda r: r.method == "GET" and "segments" in r.url and reads.append(r.url))
    page.locator("#segment-new").click()
    page.get_by_role("button", name="Record take-over").click()
    expect(rows).to_have_count(2)
    auto = page.locator("#segment-table tbody tr.auto")
    reason = page.locator("#segment-table tbody tr.child")
    expect(auto.locator("td").nth(0)).to_have_text("#1")
    expect(auto.locator("td").nth(7)).to_have_text("closed")
    expect(reason).to_have_class(re.compile(r"\bselected\b"))
    expect(reason.locator("td").nth(0)).to_have_text("#2.1")
    expect(reason.locator("td").nth(1)).to_have_text("ITO")
    expect(reason.locator("td").nth(7)).to_have_text("open")
    # No word from the live link yet: the answers' mode, as last known.
    expect(page.locator("#mode-name")).to_have_text(re.compile(r"^last known: ITO, \d+ s ago$"))
    expect(page.locator("#notice")).to_contain_text("Take-over recorded")
    page.locator("#segment-end").click()
    expect(reason.locator("td").nth(7)).to_have_text("closed")
    # Ending the reason leaves the take-over (ITO) running, and the page says so.
    expect(page.locator("#notice")).to_have_text(
        re.compile(r"Ended the reason Leg \d+ · #2\.1\. The take-over Leg \d+ · #2 goes on")
    )
    expect(page.locator("#mode-name")).to_have_text(re.compile(r"^last known: ITO, \d+ s ago$"))
    expect(page.locator("#mode-since")).to_contain_text("no open reason")
    shot(page, "take-over-ended")
    assert reads == []


def test_a_reload_shows_the_list_without_reading_it_again(page, server, open_leg, shot):
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
        robot.do("poses")
        robot.do("ito")
    finally:
        robot.stop()
    login(page, server, "otto")
    choose(page, open_leg)
    expect(page.locator("#segment-table tbody tr")).to_have_count(2)
    reads = []
    page.on("request", lambda r: r.method == "GET" and "/api/" in r.url and reads.append(r.url))
    page.reload()
    rows = page.locator("#segment-table tbody tr")
    expect(rows).to_have_count(2)
    expect(rows.filter(has_text="ITO")).to_have_count(1)
    expect(page.locator("#mode-name")).to_have_text("ITO")
    expect(page.locator("#gps-map")).to_have_attribute("data-tracks", "1")
    expect(page.locator("#collector-status")).not_to_contain_text("Asking")
    shot(page, "reloaded")
    # Catalogues, pickers and the list came with the page; the map's tracks are asked for.
    asked = {re.sub(r"[?].*|\d+", "", url.split("/api/", 1)[1]) for url in reads}
    assert "legs//tracks/" in asked
    assert not asked & {"ito-reasons/", "vehicles/", "test-events/", "shifts/", "legs/"}
    assert "legs//segments/" not in asked


def test_notes_can_be_edited_and_deleted(page, server, open_leg, shot):
    login(page, server, "otto")
    choose(page, open_leg)
    page.locator("#segment-new").click()
    row = page.locator("#segment-table tbody tr.child")
    expect(row).to_have_count(1)
    row.dblclick()
    dialog = page.locator("#segment-dialog")
    dialog.get_by_label("New note").fill("Erste Notiz")
    dialog.get_by_role("button", name="Add note").click()
    note = dialog.locator(".notes li").filter(has_text="Erste Notiz")
    note.get_by_role("button", name="Edit").click()
    dialog.get_by_label("Note text").fill("Geänderte Notiz – ÄÖÜß")
    dialog.get_by_role("button", name="Save note").click()
    edited = dialog.locator(".notes li").filter(has_text="Geänderte Notiz – ÄÖÜß")
    expect(edited).to_contain_text("edited")
    shot(page, "note-edited")
    edited.get_by_role("button", name="Delete").click()
    confirm = page.locator("#confirm-dialog")
    expect(confirm).to_contain_text("Delete this note")
    confirm.get_by_role("button", name="Delete").click()
    expect(dialog.locator(".notes li")).to_have_text(["No notes yet."])
    # An empty note is refused with the server's words, next to the field and in its label.
    dialog.get_by_role("button", name="Add note").click()
    expect(dialog.locator(".field-error")).to_have_text("New note: This field may not be blank.")
    expect(dialog.get_by_label("New note")).to_have_attribute("aria-invalid", "true")
    shot(page, "note-error")


def test_refused_edit_is_explained_in_the_dialog(page, server, open_leg, shot):
    login(page, server, "otto")
    choose(page, open_leg)
    page.locator('[data-action="edit"][data-level="event"]').click()
    dialog = page.locator("#form-dialog")
    dialog.get_by_label("Time zone").fill("Mars/Olympus")
    dialog.get_by_role("button", name="Save").click()
    expect(dialog.locator(".field-error")).to_contain_text("Time zone: 'Mars/Olympus'")
    expect(dialog).to_be_visible()
    shot(page, "time-zone-refused")
    # Fields can be cleared, and text in any script is kept.
    dialog.get_by_label("Time zone").fill("Asia/Tokyo")
    dialog.get_by_label("Location").fill("東京 テスト場")
    dialog.get_by_label("Version").fill("")
    dialog.get_by_role("button", name="Save").click()
    expect(dialog).to_be_hidden()
    expect(page.locator("#pick-event option:checked")).to_contain_text("東京 テスト場")


def test_reports_dialog_offers_exports_and_makes_a_report(page, server, open_leg, shot, tmp_path):
    login(page, server, "otto")
    choose(page, open_leg)
    page.locator("#segment-new").click()
    expect(page.locator("#segment-table tbody tr")).to_have_count(1)
    end_level(page, "event")
    expect(page.locator('[data-state="event"]')).to_have_text("closed")
    page.get_by_role("button", name="Reports & exports").click()
    dialog = page.locator("#reports-dialog")
    expect(dialog.get_by_role("link", name="Segments (CSV)")).to_be_visible()
    href = dialog.get_by_role("link", name="Segments (CSV)").get_attribute("href")
    csv = page.request.get(server.url + href)
    assert csv.ok
    archive = dialog.get_by_role("link", name="Everything (FTT archive, ZIP)").get_attribute("href")
    assert page.request.get(server.url + archive).body()[:2] == b"PK"
    # A new user meets the GPS report preselected, not an empty choice.
    expect(dialog.get_by_label("Positions")).to_have_value("false")
    # The cockpit's leg is the report's scope unless the person widens it.
    expect(dialog.get_by_label("Report of")).to_have_value("leg")
    dialog.get_by_label("Report name").fill("Abnahme Übung")
    # A zoom no tile server has is refused in words, and nothing is queued.
    dialog.get_by_label("Closest map zoom").fill("30")
    dialog.get_by_role("button", name="Generate report").click()
    expect(dialog.locator(".dialog-error")).to_contain_text("maximum map zoom")
    expect(dialog.locator("#report-list li")).to_have_count(0)
    dialog.get_by_label("Closest map zoom").fill("17")
    dialog.get_by_label("Timeline at least").fill("1.5")
    dialog.get_by_role("button", name="Generate report").click()
    entry = dialog.locator("#report-list li")
    expect(entry.first).to_contain_text("Shift 1 · Leg 1", timeout=5000)
    shot(page, "report-requested")
    # The background job finishes while the dialog is open; what it made is
    # the PDF a person downloads, so read that back.
    link = dialog.locator("#report-list li a")
    expect(link.first).to_be_visible(timeout=90_000)
    href = link.first.get_attribute("href")
    pdf = page.request.get(href if href.startswith("http") else server.url + href)
    assert pdf.ok
    text = flat(pdf_text(pdf.body(), tmp_path))
    assert "Abnahme Übung" in text and "Report of Shift 1 · Leg 1" in text
    shot(page, "report-ready")


def test_ros_parameters_are_typed_and_suggest_matching_topics(page, server, open_leg, shot):
    robot = Robot(server, open_leg)
    try:
        login(page, server, "otto")
        choose(page, open_leg)
        expect(page.locator("#collector-status")).to_contain_text("online", timeout=8000)
        page.get_by_role("button", name="ROS parameters").click()
        dialog = page.locator("#parameters-dialog")
        gps = dialog.get_by_label("topics.gps_fix")
        # Only the NavSatFix topic of the robot's graph is offered for the GPS input.
        options = dialog.locator(f"#{gps.get_attribute('list')} option")
        expect(options).to_have_count(1)
        expect(options.first).to_have_text("/fix")
        expect(dialog.get_by_label("params.use_tf")).to_have_value("true")
        expect(dialog.get_by_label("params.pose_min_distance")).to_have_attribute("type", "number")
        gps.fill("/fix")
        dialog.get_by_label("params.pose_min_distance").fill("1.5")
        # A mode-source preset fills the field, to be applied as a typed value is.
        sources = dialog.get_by_label("params.mode_sources", exact=True)
        dialog.get_by_label("params.mode_sources: start from a preset").select_option("bool")
        expect(sources).to_have_value(re.compile(r"type: std_msgs/msg/Bool, field: data"))
        shot(page, "parameters")
        dialog.get_by_role("button", name="Apply").click()
        expect(page.locator("#notice")).to_contain_text("set_parameters done", timeout=5000)
        page.get_by_role("button", name="Close").last.click()
        page.get_by_role("button", name="ROS parameters").click()
        expect(dialog.get_by_label("topics.gps_fix")).to_have_value("/fix")
        expect(dialog.get_by_label("params.pose_min_distance")).to_have_value("1.5")
        expect(sources).to_have_value(re.compile(r"std_msgs/msg/Bool"))
    finally:
        robot.stop()


BACKLOG = """
from events.models import Leg
from rosbridge_app.services import collectors
leg = Leg.objects.get(shift__vehicle__key="{key}")
collectors.heartbeat(
    "spool-{key}", vehicle=leg.shift.vehicle, logging=True, leg=leg,
    state="logging; {pending} records waiting", pending={pending}, disk="{disk}",
)
"""
DISK_FULL = "robot disk full since 14:03, 2 snapshots dropped, 40 positions thinned out"


def test_robot_panel_shows_the_collectors_backlog_and_full_disk_until_gone(page, server, open_leg):
    # What a collector reports when the database is back after an outage: the
    # records still in its spool. The operator must see that data is on its way.
    # A full robot disk (issue 32) is said beside it, until there is room again.
    server.python(BACKLOG.format(key=open_leg, pending=3356, disk=DISK_FULL))
    login(page, server, "otto")
    choose(page, open_leg)
    status = page.locator("#collector-status")
    expect(status).to_contain_text("logging into this leg · 3,356 records not yet stored")
    expect(status).to_contain_text(DISK_FULL)
    server.python(BACKLOG.format(key=open_leg, pending=0, disk=""))
    expect(status).not_to_contain_text("not yet stored", timeout=8000)
    expect(status).not_to_contain_text("robot disk")
    expect(status).to_contain_text("logging into this leg")


def test_local_map_and_overlay_appear_live(page, server, open_leg, shot):
    login(page, server, "otto")
    choose(page, open_leg)
    expect(page.locator("#live-status")).to_have_text("live")
    robot = Robot(server, open_leg)
    try:
        for step in ("auto", "poses", "ito", "poses", "map"):
            robot.do(step)
    finally:
        robot.stop()
    local = page.locator("#local-map")
    expect(local).to_be_visible(timeout=3000)
    expect(local.locator("img.ftt-affine")).to_have_count(1)
    # Two tracks and the take-over circle of the ITO segment.
    expect(local).to_have_attribute("data-tracks", "2")
    expect(local).to_have_attribute("data-take-overs", "1")
    expect(page.locator("#local-message")).to_contain_text("2×2 cells of 40 m")
    # Two segments started with both positions: the overlay is fitted and offered.
    expect(page.locator("#overlay-message")).to_contain_text("fitted from 2 segments")
    expect(page.locator("#gps-map .leaflet-control-layers")).to_have_count(1)
    shot(page, "local-map-live")


def test_phone_layout_and_delete_confirmation(browser, server, open_leg, shot):
    page = browser.new_page(viewport={"width": 390, "height": 844}, is_mobile=True)
    login(page, server, "otto")
    choose(page, open_leg)
    # Nothing wider than the phone: no sideways scrolling of the page.
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    shot(page, "phone")
    page.locator('[data-action="delete"][data-level="leg"]').click()
    confirm = page.locator("#confirm-dialog")
    expect(confirm).to_contain_text("Delete leg 1 with all its segments, notes and images?")
    shot(page, "delete-confirmation")
    confirm.get_by_role("button", name="Keep it").click()
    expect(page.locator('[data-state="leg"]')).to_have_text("open")
    page.locator('[data-action="delete"][data-level="leg"]').click()
    confirm.get_by_role("button", name="Delete").click()
    expect(page.locator("#pick-leg option")).to_have_text(["no leg yet"])
    expect(page.locator("#segments-section")).to_be_hidden()
    page.close()


def test_ending_a_leg_while_logging_stops_logging_first(page, server, open_leg, shot):
    robot = Robot(server, open_leg)
    try:
        login(page, server, "otto")
        choose(page, open_leg)
        toggle = page.locator("#logging-toggle")
        expect(toggle).to_be_enabled(timeout=8000)
        toggle.click()
        expect(toggle).to_have_text("Stop logging", timeout=5000)
        robot.do("auto")
        expect(page.locator("#segment-table tbody tr")).to_have_count(1)
        end_level(page, "leg")
        expect(page.locator('[data-state="leg"]')).to_have_text("closed")
        expect(toggle).to_have_text("Start logging", timeout=5000)
        # Closed levels: logging cannot start again until a new leg is opened.
        expect(toggle).to_be_disabled()
        expect(page.locator("#logging-why")).to_contain_text("open test event, shift and leg")
        cells = page.locator("#segment-table tbody tr td")
        expect(cells.nth(7)).to_have_text("closed")
        # The list shows the time of day; the full date and zone are in the tooltip.
        expect(cells.nth(3)).to_have_text(re.compile(r"^\d{2}:\d{2}:\d{2}$"))
        expect(cells.nth(3)).to_have_attribute("title", re.compile(r"20\d\d"))
        shot(page, "leg-ended")
    finally:
        robot.stop()


def test_tile_server_can_be_overridden_per_browser(page, server, open_leg, tiles, shot):
    login(page, server, "otto")
    choose(page, open_leg)
    gps = page.locator("#gps-map")
    expect(gps.locator("img.leaflet-tile-loaded").first).to_be_attached()
    expect(page.locator("#tile-message")).to_be_hidden()
    page.get_by_role("button", name="Map settings").click()
    settings = page.locator("#map-settings-dialog")
    settings.get_by_label("Tile URL").fill("http://127.0.0.1:9/elsewhere/{z}/{x}/{y}.png")
    settings.get_by_role("button", name="Save").click()
    expect(page.locator("#tile-message")).to_contain_text("tiles are unavailable")
    # The choice is this browser's: it survives a reload.
    page.reload()
    choose(page, open_leg)
    expect(page.locator("#tile-message")).to_contain_text("tiles are unavailable")
    shot(page, "own-tile-server-down")
    page.get_by_role("button", name="Map settings").click()
    settings.get_by_role("button", name="Use site default").click()
    expect(gps.locator("img.leaflet-tile-loaded").first).to_be_attached()
    expect(page.locator("#tile-message")).to_be_hidden()
