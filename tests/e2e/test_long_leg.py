"""The cockpit on a long leg: the segment list holds only the rows in view, the
end of the list is reached by scrolling, and a live take-over joins the list at
once without building the rows already shown again; a screen reader hears how
many rows the whole list has."""

import json
import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import login
from tests.support.screens import OVERFLOWING, SMALL, VIEWPORTS

pytestmark = pytest.mark.e2e

# The badge may first say stale when a heartbeat comes late on a busy machine.
LIVE = 15_000
MASTERS = 250

# Every other master a take-over: 125 reasons and 125 AUTO rows, 250 rows; the
# newest (the open one) is AUTO.
LONG_LEG = """
import json
from events.models import PoseSource, Vehicle
from events.services import logs, segments
PoseSource.objects.get_or_create(key="gps", defaults={{"short_description": "GPS"}})
v = Vehicle.objects.create(key={key!r}, short_description="Long Rover")
e = logs.create_test_event(location="Long field", time_zone="Europe/Berlin")
s = logs.create_shift(test_event=e, vehicle=v)
leg = logs.create_leg(shift=s, weather_id="sunny")
for i in range({masters}):
    segments.report_mode(leg, "auto" if i % 2 else "ito")
print(json.dumps({{"event": e.pk, "shift": s.pk, "leg": leg.pk}}))
"""

TAKE_OVER = """
from events.models import Leg
from events.services import segments
segments.report_mode(Leg.objects.get(pk={leg}), "ito")
"""

ROWS = "#segment-table tbody tr[data-id]"

# Whether a rendered row lies inside the list's scrolled box (rendered for where it is now).
ROW_IN_VIEW = """(sel) => {
  const box = document.querySelector("#segments-section .table-wrap").getBoundingClientRect();
  return Array.from(document.querySelectorAll(sel)).some((tr) => {
    const r = tr.getBoundingClientRect();
    return r.top >= box.top + 40 && r.bottom <= box.bottom;
  });
}"""


# The number of a rendered row inside the list's scrolled box whose place in the
# list is past the given one, or null.
ROW_IN_VIEW_BEYOND = """([sel, beyond]) => {
  const box = document.querySelector("#segments-section .table-wrap").getBoundingClientRect();
  const row = Array.from(document.querySelectorAll(sel)).find((tr) => {
    const r = tr.getBoundingClientRect();
    return Number(tr.getAttribute("aria-rowindex")) > beyond
      && r.top >= box.top + 40 && r.bottom <= box.bottom;
  });
  return row ? row.querySelector("td").textContent : null;
}"""


def cell(page, label):
    """The row whose number cell reads ``label``, if rendered."""
    number = page.locator("td:first-child", has_text=re.compile(rf"^{re.escape(label)}$"))
    return page.locator(ROWS).filter(has=number)


def open_long_leg(browser, server, key: str, screen: str):
    """A new leg of MASTERS masters for vehicle ``key``, opened in a page of ``screen``;
    returns the page and the leg's ids."""
    code = LONG_LEG.format(masters=MASTERS, key=key)
    ids = json.loads(server.python(code).strip().splitlines()[-1])
    page = browser.new_page(**VIEWPORTS[screen])
    login(page, server, "otto")
    page.goto(f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}")
    return page, ids


def in_view(row, wrap) -> bool:
    """Whether the row lies inside the list's scrolled box."""
    r, w = row.bounding_box(), wrap.bounding_box()
    if r is None:
        return False
    return r["y"] >= w["y"] - 1 and r["y"] + r["height"] <= w["y"] + w["height"] + 1


def test_a_long_leg_renders_the_rows_in_view_and_a_take_over_touches_one_row(browser, server, shot):
    page, ids = open_long_leg(browser, server, "long-rover", "tablet")
    expect(page.locator("#live-status")).to_have_text("live", timeout=LIVE)
    table = page.locator("#segment-table")
    # The whole list's rows and the header row, for a screen reader.
    expect(table).to_have_attribute("aria-rowcount", str(MASTERS + 1))
    newest = cell(page, f"#{MASTERS}")
    expect(newest).to_have_attribute("aria-rowindex", "2")
    rendered = page.locator(ROWS).count()
    assert rendered < 100, rendered

    # Scrolling to the end shows the first take-over of the leg (the list is newest first).
    wrap = page.locator("#segments-section .table-wrap")
    wrap.evaluate("(w) => { w.scrollTop = w.scrollHeight; }")
    oldest = cell(page, "#1.1")
    expect(oldest).to_be_visible()
    assert in_view(oldest, wrap)
    expect(oldest).to_have_attribute("aria-rowindex", str(MASTERS + 1))
    assert page.locator(ROWS).count() < 100
    wrap.evaluate("(w) => { w.scrollTop = 0; }")
    expect(newest).to_be_visible()
    expect(oldest).to_have_count(0)
    shot(page, "long-leg")

    # The rows on screen are marked; a live take-over must keep their nodes.
    marked = page.evaluate(
        """(sel) => Array.from(document.querySelectorAll(sel)).slice(0, 10)
            .map((tr) => { tr.__kept = true; return tr.dataset.id; })""",
        ROWS,
    )
    assert len(marked) == 10
    server.python(TAKE_OVER.format(leg=ids["leg"]))
    reason = cell(page, f"#{MASTERS + 1}.1")
    expect(reason).to_be_visible()
    expect(reason).to_have_attribute("aria-rowindex", "2")
    expect(table).to_have_attribute("aria-rowcount", str(MASTERS + 1 + 1))
    # The AUTO run it ended says so, in the same row.
    expect(cell(page, f"#{MASTERS}").locator("td").last).to_have_text("closed")
    kept = page.evaluate(
        """([sel, ids]) => ids.map((id) => {
            const tr = document.querySelector(`${sel}[data-id="${id}"]`);
            return Boolean(tr && tr.__kept);
        })""",
        [ROWS, marked],
    )
    assert kept == [True] * len(marked)
    assert page.locator(ROWS).count() < 100

    # Scrolled into the list, a row arriving at the top moves nothing in view.
    wrap.evaluate("(w) => { w.scrollTop = w.scrollHeight / 2; }")
    # A row in view once the list has rendered for the new place (the scroll
    # event comes after scrollTop is set, so the rows before it are still there).
    label = page.wait_for_function(ROW_IN_VIEW_BEYOND, arg=[ROWS, MASTERS // 4]).json_value()
    middle = cell(page, label)
    y = middle.bounding_box()["y"]
    server.python(TAKE_OVER.replace('"ito"', '"auto"').format(leg=ids["leg"]))
    expect(table).to_have_attribute("aria-rowcount", str(MASTERS + 3))
    assert cell(page, label).bounding_box()["y"] == pytest.approx(y, abs=1)
    assert page.evaluate(OVERFLOWING) == []
    page.close()


def test_the_focused_row_stays_when_it_scrolls_out_and_the_keys_reach_the_end(browser, server):
    page, _ = open_long_leg(browser, server, "long-rover-keys", "laptop")
    newest = cell(page, f"#{MASTERS}")
    expect(newest).to_be_visible()
    wrap = page.locator("#segments-section .table-wrap")
    wrap.focus()
    page.keyboard.press("ArrowDown")
    expect(newest).to_be_focused()
    # Scrolled far away, the focused row is still there, and still has the focus.
    wrap.evaluate("(w) => { w.scrollTop = w.scrollHeight / 2; }")
    expect(cell(page, "#1.1")).to_have_count(0)
    expect(newest).to_have_count(1)
    expect(newest).to_be_focused()
    # End goes to the last row of the whole list, which is then drawn.
    page.keyboard.press("End")
    oldest = cell(page, "#1.1")
    expect(oldest).to_be_focused()
    assert in_view(oldest, wrap)
    # Space selects the focused row.
    page.keyboard.press(" ")
    expect(oldest).to_have_class(re.compile(r"\bselected\b"))
    page.close()


def test_a_long_list_on_a_phone_scrolls_only_up_and_down(browser, server):
    page, _ = open_long_leg(browser, server, "long-rover-phone", "phone")
    expect(cell(page, f"#{MASTERS}")).to_be_visible()
    wrap = page.locator("#segments-section .table-wrap")
    for top in ("0", "w.scrollHeight / 2", "w.scrollHeight"):
        wrap.evaluate(f"(w) => {{ w.scrollTop = {top}; }}")
        page.wait_for_function(ROW_IN_VIEW, arg=ROWS)
        assert page.evaluate(OVERFLOWING) == []
        assert page.evaluate(SMALL, ROWS) == []
    expect(cell(page, "#1.1")).to_be_visible()
    page.close()
