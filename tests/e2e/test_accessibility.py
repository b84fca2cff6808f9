"""axe-core finds nothing on the cockpit (in a take-over), its dialogs, the fleet
and the comparison page, on a laptop, a tablet and a phone.  axe comes from npm
(node_modules), injected by the test; nothing is fetched from the internet."""

import json

import pytest
from playwright.sync_api import expect

from tests.support.browser import login
from tests.support.screens import AXE, VIEWPORTS, VIOLATIONS


def assert_clean(page, where):
    found = page.evaluate(VIOLATIONS)
    assert not found, f"{where}: " + "; ".join(found)


@pytest.fixture(scope="module")
def field(server):
    """A robot logging in a take-over (with GPS points and a finished AUTO run), and
    two closed test events to compare."""
    out = server.python(
        """
        import json
        from events.models import Vehicle
        from events.services import logs, segments
        from rosbridge_app.services import collectors
        from telemetry.services import pose_writes
        v = Vehicle.objects.create(key="axe-rover", short_description="Axe Rover")
        events = []
        for n in range(2):
            e = logs.create_test_event(location=f"Axe field {n + 1}", version=f"{n + 1}.0")
            shift = logs.create_shift(test_event=e, vehicle=v)
            leg = logs.create_leg(shift=shift, weather_id="sunny")
            auto = segments.report_mode(leg, "auto").master
            fixes = [pose_writes.GpsFix(7.0, 50.0 + i * 1e-4) for i in range(9)]
            pose_writes.store_poses(auto, fixes)
            segments.report_mode(leg, "ito", **({"reason": "safety"} if n == 0 else {}))
            events.append({"event": e.pk, "shift": leg.shift_id, "leg": leg.pk})
            if n == 0:
                segments.report_mode(leg, "auto")
                logs.close_leg(leg)
                logs.close_shift(leg.shift)
                logs.close_test_event(e)
        collectors.heartbeat("axe-rover", vehicle=v, logging=True, leg=leg)
        print(json.dumps(events))
        """
    )
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("screen", list(VIEWPORTS))
def test_cockpit_dialogs_fleet_and_compare_pass_axe(browser, server, field, shot, screen):
    assert AXE.exists(), "run npm ci (scripts/setup.sh --test) for axe-core"
    # The site's CSP rightly refuses injected scripts; axe is the test's own tool.
    context = browser.new_context(bypass_csp=True, **VIEWPORTS[screen])
    page = context.new_page()
    login(page, server, "otto")
    done, live = field
    page.goto(f"{server.url}/?event={live['event']}&shift={live['shift']}&leg={live['leg']}")
    expect(page.locator("#mode-name")).to_have_text("ITO")
    expect(page.locator("#timeline .bar")).not_to_have_count(0)
    page.add_script_tag(path=str(AXE))
    assert_clean(page, "cockpit")
    shot(page, f"{screen}-cockpit-ito")

    dialogs = {
        "form-dialog": lambda: page.locator('[data-action="new"][data-level="shift"]').click(),
        "confirm-dialog": lambda: page.locator('[data-action="delete"][data-level="leg"]').click(),
        "segment-dialog": lambda: page.locator("#segment-table tbody tr").last.dblclick(),
        "reports-dialog": lambda: page.get_by_role("button", name="Reports & exports").click(),
        "map-settings-dialog": lambda: page.get_by_role("button", name="Map settings").click(),
    }
    for name, open_it in dialogs.items():
        open_it()
        dialog = page.locator(f"#{name}")
        expect(dialog).to_be_visible()
        # The dialog's lists arrive from the API.
        expect(dialog.locator("select:empty")).to_have_count(0)
        assert_clean(page, name)
        shot(page, f"{screen}-{name}")
        page.keyboard.press("Escape")
        expect(dialog).to_be_hidden()

    page.goto(f"{server.url}/?view=fleet")
    expect(page.locator(".fleet-vehicle", has_text="Axe Rover")).to_be_visible()
    page.add_script_tag(path=str(AXE))
    assert_clean(page, "fleet")
    shot(page, f"{screen}-fleet")

    page.goto(f"{server.url}/compare/?event={done['event']}&event={live['event']}")
    expect(page.locator("#by-event article")).to_have_count(2)
    page.add_script_tag(path=str(AXE))
    assert_clean(page, "compare")
    context.close()
