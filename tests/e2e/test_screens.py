"""The cockpit at the three screens it is used on: a laptop, a tablet held in one
hand and a phone.  Nothing scrolls sideways, the main actions are big enough
to tap, and on the tablet the mode, the reasons and the map share the first screen.

Runs after test_field_walk.py (file order), whose first step needs a server
without any vehicle."""

import json
import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import login
from tests.support.screens import OVERFLOWING, SMALL, VIEWPORTS

MAIN_ACTIONS = (
    "#mode-panel .quick button, #mode-panel select, #segment-new, #segment-end, #segment-edit, "
    "#logging-toggle, .log-row button, .log-row select, #segment-table tbody tr, label.switch, "
    ".topbar nav a, .topbar nav button, .topbar nav select, #fit-track, #timeline .bar, "
    ".leaflet-control-zoom a"
)


@pytest.fixture(scope="module")
def driven_leg(server):
    """A leg with an AUTO run, a take-over and AUTO again (open), with GPS points."""
    out = server.python(
        """
        import json
        from events.models import Performer, PoseSource, Vehicle
        from events.services import logs, segments
        from telemetry.services import pose_writes
        Performer.objects.get_or_create(institution="Fraunhofer FKIE")
        PoseSource.objects.get_or_create(key="gps", defaults={"short_description": "GPS"})
        v = Vehicle.objects.create(key="cockpit-rover", short_description="Cockpit Rover")
        e = logs.create_test_event(location="Cockpit field", time_zone="Europe/Berlin")
        s = logs.create_shift(test_event=e, vehicle=v)
        leg = logs.create_leg(shift=s, weather_id="sunny")
        first = segments.report_mode(leg, "auto").master
        fixes = [pose_writes.GpsFix(7.0, 50.0 + i * 1e-4) for i in range(20)]
        pose_writes.store_poses(first, fixes)
        ito = segments.report_mode(leg, "ito").master
        fixes = [pose_writes.GpsFix(7.0 + i * 1e-4, 50.002) for i in range(5)]
        pose_writes.store_poses(ito, fixes)
        segments.report_mode(leg, "auto")
        child = ito.children.get()
        print(json.dumps({"event": e.pk, "shift": s.pk, "leg": leg.pk, "child": child.pk}))
        """
    )
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("screen", list(VIEWPORTS))
def test_cockpit_fits_the_screen(browser, server, driven_leg, shot, screen):
    page = browser.new_page(**VIEWPORTS[screen])
    login(page, server, "otto")
    ids = driven_leg
    # A shared link restores event, shift, leg and the selected take-over.
    page.goto(
        f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}"
        f"&segment={ids['child']}"
    )
    expect(page.locator("#pick-leg")).to_have_value(str(ids["leg"]))
    selected = page.locator("#segment-table tbody tr.selected")
    expect(selected).to_have_count(1)
    expect(selected.locator("td").first).to_have_text("#2.1")
    expect(page.locator("#mode-name")).to_have_text("AUTO")
    # Which robot, event and shift this is, in the banner's first screen at every size.
    whom = page.locator("#mode-whom")
    expect(whom).to_have_text("Cockpit Rover · Cockpit field · Shift 1 · Leg 1")
    box = whom.bounding_box()
    assert box["y"] >= 0 and box["y"] + box["height"] <= page.viewport_size["height"]
    # The strip says what each bar is in words and has a time axis (24 h clock).
    expect(page.locator("#timeline .bar")).to_have_count(3)
    expect(page.locator("#timeline .bar.ito")).to_have_attribute("aria-label", re.compile("ITO"))
    expect(page.locator("#timeline .axis span")).to_have_count(3)
    expect(page.locator("#timeline .axis span").first).to_have_text(re.compile(r"^\d\d:\d\d:\d\d$"))
    expect(page.locator("#collector")).to_be_visible()
    page.wait_for_timeout(300)  # the map's fit animation
    shot(page, f"{screen}-cockpit")
    if screen == "phone":
        # The header leaves the phone's screen to the cockpit.
        assert page.locator(".topbar").bounding_box()["height"] <= 0.2 * 844

    assert page.evaluate(OVERFLOWING) == []
    assert page.evaluate(SMALL, MAIN_ACTIONS) == []

    if screen == "tablet":
        height = page.viewport_size["height"]
        for part in ("#mode-panel", "[data-quick='safety']", "#reason-apply", "#gps-map"):
            box = page.locator(part).bounding_box()
            assert box["y"] >= 0 and box["y"] + box["height"] <= height, part
        for part in ("#segment-table tbody tr >> nth=0", "#collector"):
            assert page.locator(part).bounding_box()["y"] < height, part

    # Quick reasons annotate the open take-over: in AUTO there is none, and the
    # buttons say so whichever row is selected (an earlier one gets its reason in its dialog).
    expect(page.locator("#quick-target")).to_have_text("No open take-over")
    expect(page.locator("[data-quick='safety']")).to_be_disabled()
    page.close()


def test_dialogs_write_nothing_until_save(browser, server, driven_leg, shot):
    page = browser.new_page(**VIEWPORTS["tablet"])
    login(page, server, "otto")
    ids = driven_leg
    page.goto(f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}")
    rows = page.locator("#segment-table tbody tr")
    expect(rows).to_have_count(3)
    legs = page.locator("#pick-leg option")
    expect(legs).to_have_count(2)

    # New leg: weather is "—" until chosen; Cancel leaves no leg behind.
    page.locator('[data-action="new"][data-level="leg"]').click()
    dialog = page.locator("#form-dialog")
    expect(dialog.get_by_label("Weather")).to_have_value("")
    expect(dialog.get_by_label("Weather").locator("option:checked")).to_have_text("—")
    shot(page, "new-leg-dialog")
    assert page.evaluate(OVERFLOWING) == []
    dialog.get_by_role("button", name="Cancel").click()
    expect(dialog).to_be_hidden()
    expect(legs).to_have_count(2)

    # New in AUTO asks first; Cancel records nothing.
    page.locator("#segment-new").click()
    confirm = page.locator("#confirm-dialog")
    expect(confirm).to_contain_text("The robot is in AUTO")
    expect(confirm.locator(".undo-warning")).to_be_hidden()
    shot(page, "take-over-question")
    confirm.get_by_role("button", name="Cancel").click()
    expect(rows).to_have_count(3)
    page.locator("#segment-new").click()
    confirm.get_by_role("button", name="Record take-over").click()
    expect(rows).to_have_count(4)
    expect(page.locator("#notice")).to_have_text("Take-over recorded.")
    expect(page.locator("#mode-name")).to_have_text("ITO")
    shot(page, "take-over-recorded")
    page.close()


# Every vehicle name on the fleet map, with how far it sticks out of the map (px).
LABELS_OUTSIDE = """() => {
  const map = document.querySelector("#fleet-map").getBoundingClientRect();
  return Array.from(document.querySelectorAll("#fleet-map .leaflet-tooltip")).map((t) => {
    const r = t.getBoundingClientRect();
    const out = Math.max(
      map.left - r.left, r.right - map.right, map.top - r.top, r.bottom - map.bottom);
    return [t.textContent, Math.round(out)];
  });
}"""


def test_fleet_names_stay_on_the_map_on_a_phone(browser, server, shot):
    """Two robots side by side east-west: fitted, each dot is near an edge of the
    phone's narrow map, and each name must still be readable on the map."""
    server.python(
        """
        from events.models import Vehicle
        from events.services import logs, segments
        from rosbridge_app.services import collectors
        from telemetry.services import pose_writes
        for name, lon in (("West", 7.20), ("East", 7.21)):
            v = Vehicle.objects.create(key=f"edge-{name}", short_description=f"Edge rover {name}")
            e = logs.create_test_event(location=f"Edge field {name}")
            leg = logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v))
            auto = segments.report_mode(leg, "auto").master
            pose_writes.store_poses(auto, [pose_writes.GpsFix(lon, 50.3)])
            collectors.heartbeat(f"edge-{name}", vehicle=v, logging=True, leg=leg)
        """
    )
    page = browser.new_page(**VIEWPORTS["phone"])
    login(page, server, "otto")
    page.goto(f"{server.url}/?view=fleet")
    for name in ("West", "East"):
        expect(
            page.locator("#fleet-map .leaflet-tooltip", has_text=f"Edge rover {name}")
        ).to_be_visible()
    page.wait_for_timeout(300)  # the fit animation
    shot(page, "phone-fleet")
    labels = page.evaluate(LABELS_OUTSIDE)
    assert {name for name, _ in labels} >= {"Edge rover West", "Edge rover East"}
    assert [name for name, out in labels if out > 0] == []
    # A cockpit opened from the fleet: the browser's Back returns to the fleet.
    page.locator(".fleet-vehicle", has_text="Edge rover West").click()
    expect(page.locator("#cockpit")).to_be_visible()
    page.go_back()
    expect(page.locator("#fleet-view")).to_be_visible()
    expect(page).to_have_url(re.compile(r"view=fleet"))
    page.close()


def test_new_shift_says_it_ends_the_vehicles_open_shift(browser, server, driven_leg, shot):
    """Last of the driven leg's tests: it ends that shift."""
    # A second vehicle, so that none is preselected.
    server.python(
        """
        from events.models import Vehicle
        Vehicle.objects.get_or_create(key="spare-rover", defaults={"short_description": "Spare"})
        """
    )
    page = browser.new_page(**VIEWPORTS["tablet"])
    login(page, server, "otto")
    ids = driven_leg
    page.goto(f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}")
    expect(page.locator("#pick-shift option")).to_have_count(2)
    page.locator('[data-action="new"][data-level="shift"]').click()
    dialog = page.locator("#form-dialog")
    vehicle = dialog.get_by_label("Vehicle")
    # No choice made yet is said so; Save is in the tablet's screen without scrolling.
    expect(vehicle.locator("option:checked")).to_have_text("— choose —")
    save = dialog.get_by_role("button", name="Save")
    box = save.bounding_box()
    assert box["y"] + box["height"] <= page.viewport_size["height"]
    vehicle.select_option(label="Cockpit Rover")
    shot(page, "new-shift-dialog")
    save.click()
    confirm = page.locator("#confirm-dialog")
    expect(confirm).to_contain_text("Cockpit Rover still has Shift 1")
    confirm.get_by_role("button", name="Cancel").click()
    expect(dialog).to_be_visible()
    expect(page.locator("#pick-shift option")).to_have_count(2)
    save.click()
    confirm.get_by_role("button", name="End it and create").click()
    expect(page.locator("#notice")).to_have_text("Shift created. Shift 1 of Cockpit Rover ended.")
    expect(page.locator("#pick-shift option")).to_have_count(3)
    page.close()
