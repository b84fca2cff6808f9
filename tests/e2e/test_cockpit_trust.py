"""A cockpit an operator can trust on a flaky link: quick reasons land on the
take-over that is open now, and a dead link never looks live."""

import re
import time

import pytest
from playwright.sync_api import expect

from tests.support.browser import Robot, choose_event, login
from tests.support.screens import VIEWPORTS

pytestmark = pytest.mark.e2e


def row(page, label):
    number = page.locator("td:first-child", has_text=re.compile(rf"^{re.escape(label)}$"))
    return page.locator("#segment-table tbody tr").filter(has=number)


def test_a_quick_reason_goes_to_the_open_take_over_not_the_selected_row(
    page, server, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("ito")
        robot.do("auto")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        login(page, server, "otto")
        choose_event(page, open_leg)
        safety = page.get_by_role("button", name="Safety", exact=True)
        # In AUTO no take-over is open: the buttons say so instead of greying out silently.
        expect(page.locator("#quick-target")).to_have_text("No open take-over")
        expect(safety).to_be_disabled()
        # The operator looks at the old take-over; meanwhile the robot starts a new one.
        row(page, "#1.1").click()
        expect(row(page, "#1.1")).to_have_class(re.compile(r"\bselected\b"))
        robot.do("ito")
        expect(page.locator("#quick-target")).to_have_text("Reason for #3.1:")
        expect(safety).to_be_enabled()
        for screen, options in VIEWPORTS.items():
            page.set_viewport_size(options["viewport"])
            expect(page.locator("#quick-target")).to_be_in_viewport()
            shot(page, f"{screen}-ito")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        safety.click()
    finally:
        robot.stop()
    expect(page.locator("#notice")).to_have_text("Reason of Leg 1 · #3.1 set to Safety.")
    expect(row(page, "#3.1").locator("td").nth(2)).to_have_text("Safety")
    expect(row(page, "#1.1").locator("td").nth(2)).to_have_text("Unassigned")
    # What the server stored, read afresh.
    page.reload()
    expect(row(page, "#3.1").locator("td").nth(2)).to_have_text("Safety")
    expect(row(page, "#1.1").locator("td").nth(2)).to_have_text("Unassigned")


def test_a_stalled_link_is_shown_stale_within_5_s_and_catches_up(
    page, server, link, open_leg, shot
):
    robot = Robot(server, open_leg)
    try:
        robot.do("auto")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        login(page, link, "otto")
        choose_event(page, open_leg)
        badge, mode = page.locator("#live-status"), page.locator("#mode-name")
        expect(badge).to_have_text("live")
        expect(mode).to_have_text("AUTO")
        shot(page, "tablet-auto")
        # Half-open: the socket stays open, nothing gets through either way.
        link.stall()
        stalled = time.monotonic()
        expect(badge).to_have_text("stale", timeout=5000)
        expect(mode).to_contain_text(re.compile(r"^last known: AUTO, \d+ s ago$"), timeout=5000)
        assert time.monotonic() - stalled <= 5
        expect(page.locator("#mode-panel")).to_have_attribute("data-link", "lost")
        # The robot panel keeps no input's age from before the stall as if it were now.
        expect(page.locator("#collector-status")).to_have_text(
            re.compile("^The server cannot be reached"), timeout=15_000
        )
        expect(page.locator("#collector-inputs li")).to_have_count(0)
        for screen, options in VIEWPORTS.items():
            page.set_viewport_size(options["viewport"])
            shot(page, f"{screen}-stale")
        page.set_viewport_size(VIEWPORTS["tablet"]["viewport"])
        robot.do("ito")
        link.restore()
        expect(badge).to_have_text("live", timeout=10_000)
        # Caught up from the change feed: the mode the robot switched to meanwhile.
        expect(mode).to_have_text("ITO", timeout=5000)
        expect(page.locator("#mode-panel")).to_have_attribute("data-link", "live")
    finally:
        robot.stop()


def test_the_robot_panel_tells_dropped_messages_from_publisher_gaps(page, server, open_leg):
    # A loaded simulator's heartbeat (issue 45): 724 fixes it never sent, 3 the collector dropped.
    server.python(
        f"""
        from django.utils import timezone
        from events.models import Leg
        from rosbridge_app.services import collectors
        leg = Leg.objects.get(shift__vehicle__key="{open_leg}")
        gps = {{"count": 900, "last_received": timezone.now().isoformat(), "rate": 9.6,
                "dropped": 3, "publisher_gaps": 724}}
        collectors.heartbeat(
            "{open_leg}", vehicle=leg.shift.vehicle, logging=True, leg=leg,
            inputs={{"gps_fix": gps}},
        )
        """
    )
    login(page, server, "otto")
    choose_event(page, open_leg)
    expect(page.locator("#collector-inputs li")).to_have_text(
        re.compile(r"^gps_fix: [\d.]+ s ago · 3 dropped · publisher gaps: about 724$")
    )
