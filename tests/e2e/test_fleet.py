"""The fleet view with two simulated robots logging at once: two ftt_simulate +
ftt_collect pairs over real ROS 2, each robot in its own namespace, writing
into PostgreSQL as a fleet in the field does.

Both robots appear on one map in their mode's colour and move live; one tap
on a robot opens its cockpit, and the address keeps the choice."""

import json
import time

import pytest
from playwright.sync_api import expect

from tests.support.browser import ARTIFACTS, login
from tests.support.ros import Processes, copy_default_params, requires_ros
from tests.support.screens import OVERFLOWING, SMALL, VIEWPORTS

pytestmark = [pytest.mark.e2e, requires_ros]

# The cockpit's colours for the modes (static/gui/maps.js).
AUTO_COLOUR, ITO_COLOUR = "#1a9c3a", "#d22020"
FLEET_ACTIONS = "#toggle-fleet, #fleet-fit, .fleet-vehicle"
# Each expectation may wait this long: the machine is shared with four ROS processes.
SLOW = 30_000
# Minutes on a loaded machine: two ROS processes per robot start and discover each other.
STARTUP_MS = 120_000


@pytest.fixture(scope="module")
def two_robots(postgres_server, tmp_path_factory):
    server = postgres_server
    """Robot "alpha" drives in AUTO, robot "bravo" is taken over (ITO), both for good."""
    tmp = tmp_path_factory.mktemp("fleet")
    run = int(time.time() * 1000) % 1_000_000
    robots = {
        "alpha": {"key": f"alpha-{run}", "mode": "auto", "lat": 50.6160, "lon": 7.1285},
        "bravo": {"key": f"bravo-{run}", "mode": "ito", "lat": 50.6166, "lon": 7.1297},
    }
    for name, robot in robots.items():
        out = server.python(
            f"""
            import json
            from events.models import Vehicle
            from events.services import logs
            vehicle = Vehicle.objects.create(
                key={robot["key"]!r}, short_description="Rover {name.title()}"
            )
            event = logs.create_test_event(location="Fleet field {name}")
            shift = logs.create_shift(test_event=event, vehicle=vehicle)
            leg = logs.create_leg(shift=shift)
            ids = {{"vehicle": vehicle.pk, "leg": leg.pk, "shift": shift.pk, "event": event.pk}}
            print(json.dumps(ids))
            """
        )
        robot.update(json.loads(out.strip().splitlines()[-1]))
    # The robots' logs are kept with the screenshots: when one never shows, they say why.
    logs = ARTIFACTS / "fleet-robots"
    logs.mkdir(parents=True, exist_ok=True)
    processes = Processes(logs, {**server.env, "PYTHONUNBUFFERED": "1"})
    try:
        for name, robot in robots.items():
            namespace = f"/fleet_{name}_{run}"
            processes.start(
                "ftt_simulate",
                "--prefix",
                namespace,
                "--first-mode",
                robot["mode"],
                "--switch-every",
                "0",
                "--latitude",
                str(robot["lat"]),
                "--longitude",
                str(robot["lon"]),
                "--speed",
                "3",
                "--gps-rate",
                "2",
                "--tf-rate",
                "5",
                "--camera-rate",
                "0",
                "--map-size",
                "40",
                name=f"sim-{name}",
            )
            # Each robot's transforms in its namespace (docs/collector.md, Tools).
            params = copy_default_params(
                tmp, vehicle=robot["key"], **{"topics.tf": "tf", "topics.tf_static": "tf_static"}
            ).rename(tmp / f"{name}.yaml")
            processes.start(
                "ftt_collect",
                "--vehicle",
                robot["key"],
                "--name",
                f"fleet-{name}-{run}",
                "--params-file",
                str(params),
                "--start-logging",
                "--ros-args",
                "-r",
                f"__ns:={namespace}",
                name=f"collector-{name}",
            )
        # The four processes take a while to start on a loaded machine; the page
        # is asked only once both robots log positions.
        legs = [robot["leg"] for robot in robots.values()]
        server.python(
            f"""
            import time
            from telemetry.models import Pose
            end = time.monotonic() + {STARTUP_MS / 1000}
            while time.monotonic() < end:
                if all(Pose.objects.filter(segment__leg_id=leg).exists() for leg in {legs!r}):
                    break
                time.sleep(1)
            else:
                raise SystemExit("the robots logged no positions")
            """,
            timeout=STARTUP_MS / 1000 + 60,
        )
        yield robots
    finally:
        processes.stop_all()


def fleet_page(browser, server, user):
    page = browser.new_page(**VIEWPORTS["tablet"])
    # Four ROS processes share the machine with the server: generous waits.
    page.set_default_timeout(60_000)
    page.set_default_navigation_timeout(120_000)
    login(page, server, user)
    return page


def wait_for_both(page, robots):
    for robot in robots.values():
        item = page.locator(f'.fleet-vehicle[data-vehicle="{robot["vehicle"]}"]')
        expect(item).to_have_attribute("data-mode", robot["mode"], timeout=STARTUP_MS)
        marker = page.locator(f"path.vehicle-{robot['vehicle']}")
        colour = AUTO_COLOUR if robot["mode"] == "auto" else ITO_COLOUR
        expect(marker).to_have_attribute("fill", colour, timeout=STARTUP_MS)


def marker_shape(page, vehicle_id):
    """Where the vehicle's marker is drawn: its outline on the map."""
    return page.locator(f"path.vehicle-{vehicle_id}").get_attribute("d")


def test_two_logging_robots_appear_in_their_mode_colours_and_move_live(
    browser, postgres_server, two_robots, shot
):
    server = postgres_server
    page = fleet_page(browser, server, "vera")
    page.goto(f"{server.url}/?view=fleet")
    expect(page.locator("#fleet-view")).to_be_visible(timeout=SLOW)
    expect(page.locator("#cockpit")).to_be_hidden(timeout=SLOW)
    wait_for_both(page, two_robots)
    alpha, bravo = two_robots["alpha"], two_robots["bravo"]
    expect(page.locator(f'.fleet-vehicle[data-vehicle="{alpha["vehicle"]}"]')).to_contain_text(
        "Rover Alpha", timeout=SLOW
    )
    expect(page.locator(f'.fleet-vehicle[data-vehicle="{bravo["vehicle"]}"]')).to_contain_text(
        "last take-over", timeout=SLOW
    )

    before = marker_shape(page, alpha["vehicle"])
    # The robot drives on: its marker is drawn somewhere else (the map does not pan).
    expect(page.locator(f"path.vehicle-{alpha['vehicle']}")).not_to_have_attribute(
        "d", before, timeout=30_000
    )

    for screen, options in VIEWPORTS.items():
        page.set_viewport_size(options["viewport"])
        page.locator("#fleet-fit").click()
        page.wait_for_timeout(400)  # the map's fit animation
        shot(page, f"{screen}-fleet")
        assert page.evaluate(OVERFLOWING) == [], screen
        assert page.evaluate(SMALL, FLEET_ACTIONS) == [], screen
    page.close()


def test_one_tap_on_a_robot_opens_its_cockpit_and_the_address_keeps_it(
    browser, postgres_server, two_robots, shot
):
    server = postgres_server
    page = fleet_page(browser, server, "otto")
    # With two robots logging a bare address opens the fleet by itself
    # (tests/gui/test_pages.py); the address names it here so the start is the same.
    page.goto(f"{server.url}/?view=fleet")
    expect(page.locator("#fleet-view")).to_be_visible(timeout=SLOW)
    wait_for_both(page, two_robots)

    alpha, bravo = two_robots["alpha"], two_robots["bravo"]
    page.locator(f"path.vehicle-{alpha['vehicle']}").tap()
    expect(page.locator("#cockpit")).to_be_visible(timeout=SLOW)
    expect(page.locator("#fleet-view")).to_be_hidden(timeout=SLOW)
    expect(page.locator("#pick-leg")).to_have_value(str(alpha["leg"]), timeout=SLOW)
    expect(page.locator("#mode-name")).to_have_text("AUTO", timeout=SLOW)
    expected = f"?event={alpha['event']}&shift={alpha['shift']}&leg={alpha['leg']}"
    expect(page).to_have_url(f"{server.url}/{expected}", timeout=SLOW)
    shot(page, "tablet-cockpit-of-alpha")

    page.locator("#toggle-fleet").click()
    page.locator(f'.fleet-vehicle[data-vehicle="{bravo["vehicle"]}"]').tap()
    expect(page.locator("#pick-leg")).to_have_value(str(bravo["leg"]), timeout=SLOW)
    expect(page.locator("#mode-name")).to_have_text("ITO", timeout=SLOW)
    page.reload()
    expect(page.locator("#pick-leg")).to_have_value(str(bravo["leg"]), timeout=SLOW)
    expect(page.locator("#fleet-view")).to_be_hidden(timeout=SLOW)
    page.close()
