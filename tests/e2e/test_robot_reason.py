"""The robot's reason for a take-over (params.reason_rules) waits in the cockpit
for one tap, and only that tap makes it the take-over's reason."""

import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import Robot, choose_event, login

pytestmark = pytest.mark.e2e


def test_the_robots_reason_is_confirmed_with_one_tap(page, server, open_leg):
    robot = Robot(server, open_leg)
    try:
        robot.do("ito:safety")
        login(page, server, "otto")
        choose_event(page, open_leg)
        suggestion = page.locator("#reason-suggested")
        expect(suggestion).to_have_text("Robot says: Safety ✓")
        taken = page.locator("#segment-table tbody tr", has_text=re.compile(r"#1\.1"))
        expect(taken).to_contain_text("Unassigned")
        box = suggestion.bounding_box()
        assert box["height"] >= 44 and box["width"] >= 44
        suggestion.click()
        expect(taken).to_contain_text("Safety")
        expect(suggestion).to_be_hidden()
    finally:
        robot.stop()
