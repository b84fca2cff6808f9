"""Black-box snapshots in the browser: the segment dialog lists them with a
download, and "Snapshot now" asks a real collector (ftt_collect beside a
simulated robot, over ROS 2) for one, which then appears in the dialog."""

import itertools
import os
import time

import pytest
from playwright.sync_api import expect

from tests.support.browser import choose_event, login, open_leg_code
from tests.support.ros import DOMAIN_ID, Processes, copy_default_params, requires_ros
from tests.support.screens import SMALL, VIEWPORTS

pytestmark = [pytest.mark.e2e, requires_ros]

MCAP_MAGIC = b"\x89MCAP0\r\n"
_numbers = itertools.count(1)


def open_take_over(page):
    # An ITO master is listed through its reasons; their dialog shows its snapshots.
    page.locator("#segment-table tbody tr.child").first.dblclick()
    dialog = page.locator("#segment-dialog")
    expect(dialog).to_be_visible()
    return dialog


@pytest.fixture
def leg_with_snapshot(server):
    """An ITO take-over with a real MCAP snapshot of three GPS fixes attached."""
    key = f"boxed-{next(_numbers)}-{int(time.time() * 1000) % 100000}"
    server.python(open_leg_code(key))
    server.python(
        f"""
        import tempfile
        from datetime import timedelta
        from pathlib import Path
        from django.utils import timezone
        from events.models import Vehicle
        from events.selectors.logs import open_leg_for_vehicle
        from events.services import segments
        from telemetry.services.attachments import attach_recording
        from tests.support.mcap_files import write_fixes

        leg = open_leg_for_vehicle(Vehicle.objects.get(key="{key}"))
        master = segments.report_mode(leg, "ito").master
        path = Path(tempfile.mkdtemp()) / "snapshot-20260704-101500-0a1b2c3d.mcap"
        topics = write_fixes(path, [50.6, 50.61, 50.62])
        start = timezone.now() - timedelta(seconds=30)
        attach_recording(
            master, path=path, start=start, end=start + timedelta(seconds=30),
            topics=topics, reason="switch to ITO",
        )
        """
    )
    return key


def test_the_segment_dialog_lists_snapshots_for_download(browser, server, leg_with_snapshot, shot):
    for name, screen in VIEWPORTS.items():
        viewport = screen["viewport"]
        page = browser.new_page(viewport=viewport)
        login(page, server, "vera")  # viewers may download, as images
        choose_event(page, leg_with_snapshot)
        dialog = open_take_over(page)
        rows = dialog.locator(".snapshots li")
        expect(rows).to_have_count(1)
        row = rows.first
        expect(row).to_contain_text("snapshot-20260704-101500-0a1b2c3d.mcap")
        expect(row).to_contain_text("30 s")
        expect(row).to_contain_text("/gps_fix (3)")
        expect(row).to_contain_text(" kB")
        link = row.get_by_role("link", name="Download")
        assert page.evaluate(SMALL, ".snapshots li button, .snapshots li a.button") == []
        assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]
        shot(page, f"snapshots-{name}")
        # The browser's own session fetches the file, as the link would.
        response = page.request.get(link.get_attribute("href"))
        assert response.status == 200
        assert response.body().startswith(MCAP_MAGIC)
        assert "attachment" in response.headers["content-disposition"]
        page.close()


@pytest.fixture
def robot(server, tmp_path):
    """A simulated robot (ftt_simulate, in ITO for the whole test) and its real
    collector (ftt_collect, logging, snapshots of 3 s before and 1 s after),
    both writing into the server's database."""
    key = f"live-box-{next(_numbers)}-{int(time.time() * 1000) % 100000}"
    server.python(open_leg_code(key))
    env = {
        **server.env,
        "ROS_DOMAIN_ID": str(DOMAIN_ID),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "PYTHONUNBUFFERED": "1",
        "FTT_LOG_LEVEL": "INFO",
    }
    env.pop("RMW_IMPLEMENTATION", None)
    params = copy_default_params(
        tmp_path, vehicle=key, **{"snapshot.before": 3.0, "snapshot.after": 1.0}
    )
    procs = Processes(tmp_path, env)
    procs.start(
        "ftt_simulate",
        "--switch-every",
        "3600",
        "--gps-rate",
        "10",
        "--tf-rate",
        "10",
        "--camera-rate",
        "0",
        "--map-size",
        "100",
        name="robot",
    )
    collector = procs.start(
        "ftt_collect",
        "--params-file",
        str(params),
        "--name",
        key,
        "--spool",
        str(tmp_path / "spool.sqlite3"),
        "--start-logging",
        name="collector",
    )
    yield key
    procs.stop_all()
    if os.environ.get("FTT_E2E_VERBOSE"):
        print(collector.output()[-3000:])


def test_snapshot_now_asks_the_collector_and_the_snapshot_appears(page, server, robot, shot):
    login(page, server, "otto")
    choose_event(page, robot)
    # Starting two ROS processes takes a while on a loaded machine.
    status = page.locator("#collector-status")
    expect(status).to_contain_text("logging into this leg", timeout=90_000)
    expect(page.locator("#segment-table tbody tr.child")).not_to_have_count(0, timeout=60_000)
    # The snapshot parameters are edited like the others.
    page.get_by_role("button", name="ROS parameters").click()
    parameters = page.locator("#parameters-dialog")
    expect(parameters.get_by_label("snapshot.before")).to_have_value("3")
    expect(parameters.get_by_label("snapshot.enabled")).to_have_value("true")
    parameters.get_by_role("button", name="Close").click()

    button = page.get_by_role("button", name="Snapshot now")
    expect(button).to_be_enabled(timeout=10_000)
    button.click()
    expect(page.locator("#notice")).to_contain_text("Robot: Snapshot", timeout=30_000)
    panel = page.locator("#collector")
    for name, screen in VIEWPORTS.items():
        viewport = screen["viewport"]
        page.set_viewport_size(viewport)
        panel.scroll_into_view_if_needed()
        assert page.evaluate(SMALL, "#collector button, #collector a.button") == []
        assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]
        shot(page, f"snapshot-requested-{name}")
    page.set_viewport_size(VIEWPORTS["laptop"]["viewport"])
    dialog = open_take_over(page)
    # Stored once its window (1 s after) has passed and the outbox is written.
    row = dialog.locator(".snapshots li", has_text="on request")
    expect(row).to_have_count(1, timeout=60_000)
    expect(row).to_contain_text("/gps_fix")
    # The list stays, its rows are redrawn on every change the feed brings.
    dialog.locator(".snapshots").scroll_into_view_if_needed()
    shot(page, "snapshot-listed")
    count = server.python(
        f"""
        from telemetry.models import Recording
        print("RECORDINGS", Recording.objects.filter(
            segment__leg__shift__vehicle__key="{robot}", reason="on request").count())
        """
    )
    assert "RECORDINGS 1" in count
