"""Test plans in the GUI (issue 29): the operator chooses a test case when starting
a leg and sees its progress move while the robot drives; on the comparison page a
drawn rectangle finds the take-over, and two legs' routes are compared."""

import json
import re
from pathlib import Path

import pytest
from playwright.sync_api import expect

from tests.support.browser import Robot, choose_event, login
from tests.support.screens import OVERFLOWING, VIEWPORTS

pytestmark = pytest.mark.e2e

# The robot starts at 7.1 E, 50.6 N and drives north-east (tests/support/browser.py).
CASE = """
import json
from django.contrib.gis.geos import LineString, MultiPolygon, Polygon
from events.models import Criterion, TestCase, TestEvent, Vehicle
event = TestEvent.objects.get(location="Gelände {key}")
case = TestCase.objects.create(
    test_event=event, key="gravel-loop", title="Gravel loop", planned_runs=2,
    area=MultiPolygon(Polygon.from_bbox((7.099, 50.599, 7.104, 50.603))),
    route=LineString((7.1, 50.6), (7.102, 50.602), srid=4326),
)
Criterion.objects.create(test_case=case, kind="distance_without_intervention", value=500)
vehicle = Vehicle.objects.get(key="{key}").pk
print(json.dumps({{"event": event.pk, "case": case.pk, "vehicle": vehicle}}))
"""


def progress_metres(page) -> int:
    text = page.locator("#test-case-progress").inner_text()
    return int(re.search(r"(\d+) m of 500 m", text).group(1))


def new_leg(page, case: str | None):
    page.locator('[data-action="new"][data-level="leg"]').click()
    dialog = page.locator("#form-dialog")
    select = dialog.locator('select[name="test_case"]')
    # The dialog offers this test event's cases only.
    expect(select.locator("option")).to_have_text(["—", "Gravel-loop: Gravel loop"])
    if case:
        select.select_option(label=case)
    dialog.get_by_role("button", name="Save").click()
    # The shift's open leg ends: the cockpit asks first.
    page.locator("#confirm-dialog").get_by_role("button", name="End it and create").click()
    expect(dialog).to_be_hidden()


def test_test_case_progress_search_and_route_comparison(browser, server, open_leg, shot):
    ids = json.loads(server.python(CASE.format(key=open_leg)).strip().splitlines()[-1])
    page = browser.new_page(**VIEWPORTS["tablet"])
    login(page, server, "otto")
    choose_event(page, open_leg)
    robot = Robot(server, open_leg)
    try:
        new_leg(page, "Gravel-loop: Gravel loop")
        expect(page.locator("#pick-leg option:checked")).to_contain_text("Leg 2")
        box = page.locator("#test-case")
        expect(box).to_contain_text("gravel-loop: Gravel loop")
        expect(page.locator("#test-case-progress")).to_have_text(
            "run 1 of 2 · 0 m of 500 m without intervention"
        )
        robot.do("auto")
        robot.do("poses")
        # The live feed's positions move the progress line without a reload.
        expect(page.locator("#test-case-progress")).not_to_contain_text(" 0 m of 500 m")
        driven = progress_metres(page)
        assert 30 < driven < 500
        page.locator("#test-case summary").click()
        expect(page.locator("#test-case-criteria li")).to_have_text(
            ["distance without intervention ≥ 500 (m) not yet"]
        )
        shot(page, "cockpit-progress")
        robot.do("poses")
        expect(page.locator("#test-case-progress")).not_to_contain_text(f" {driven} m of")
        assert progress_metres(page) > driven
        robot.do("ito:safety")
        # A second, unplanned leg driven further on: the route to compare with.
        new_leg(page, None)
        expect(page.locator("#test-case")).to_be_hidden()
        robot.do("auto")
        for _ in range(3):
            robot.do("poses")
    finally:
        robot.stop()

    page.goto(f"{server.url}/compare/")
    form = page.locator("#search-form")
    form.get_by_label("Vehicle").select_option(str(ids["vehicle"]))
    # The case's area frames the map; the rectangle drawn inside it holds the take-over.
    form.get_by_label("Test case's area").select_option(
        label=f"#{ids['event']} gravel-loop: Gravel loop"
    )
    page.get_by_role("button", name="Draw area").click()
    # Mouse clicks are in the window's coordinates: the whole map in sight first.
    page.locator("#search-map").evaluate("(map) => map.scrollIntoView({block: 'center'})")
    map_box = page.locator("#search-map").bounding_box()
    for (fx, fy), then in (
        ((0.1, 0.1), "Click the opposite corner."),
        ((0.9, 0.9), "Area drawn. Press Search."),
    ):
        page.mouse.click(
            map_box["x"] + fx * map_box["width"], map_box["y"] + fy * map_box["height"]
        )
        expect(page.locator("#search-status")).to_have_text(then)
    page.get_by_role("button", name="Search", exact=True).click()
    expect(page.locator("#search-status")).to_have_text("1 take-over found.")
    expect(page.locator("#search-results li")).to_have_count(1)
    expect(page.locator("#search-results li")).to_contain_text(f"Gelände {open_leg} · Leg 2 · #")
    csv = page.request.get(server.url + page.locator("#search-csv").get_attribute("href"))
    assert csv.ok and len(csv.text().strip().splitlines()) == 2  # header and the take-over
    # The link itself sends the search by POST (an area may not fit in an address).
    with page.expect_download() as clicked:
        page.locator("#search-csv").click()
    sheet = Path(clicked.value.path()).read_text(encoding="utf-8")
    assert len(sheet.strip().splitlines()) == 2
    shot(page, "search")

    routes = page.locator("#routes-form")
    legs = page.request.get(f"{server.url}/api/legs/?test_event={ids['event']}").json()
    by_number = {leg["number"]: leg["id"] for leg in legs["results"]}
    shift = legs["results"][0]["shift"]
    routes.get_by_label("First leg").select_option(str(by_number[2]))
    routes.get_by_label("Second route").select_option(str(by_number[3]))
    routes.get_by_label("Threshold (m)").fill("5")
    page.get_by_role("button", name="Compare routes").click()
    card = page.locator("#routes-figures article")
    expect(card).to_have_count(1)
    answer = page.request.get(
        f"{server.url}/api/reports/routes/?leg={by_number[2]}&leg={by_number[3]}&threshold=5"
    ).json()
    frechet = f"{answer['pairs'][0]['frechet']:.1f} m"
    expect(card).to_contain_text(f"Discrete Fréchet distance{frechet}")
    # The second leg drove on beyond the first: its far stretch is drawn in red.
    expect(page.locator("#routes-map path.beyond").first).to_be_visible()
    expect(page.locator("#routes-legend li")).to_have_text(
        [
            re.compile(r"^A: .*Leg 2"),
            re.compile(r"^B: .*Leg 3"),
            "more than 5 m from the other route",
        ]
    )
    shot(page, "routes")
    # The first leg against the test case's planned route.
    routes.get_by_label("Second route").select_option(
        label=f"#{ids['event']} gravel-loop: Gravel loop (planned)"
    )
    page.get_by_role("button", name="Compare routes").click()
    planned = page.request.get(
        f"{server.url}/api/reports/routes/?leg={by_number[2]}&case={ids['case']}&threshold=5"
    ).json()
    frechet = f"{planned['pairs'][0]['frechet']:.1f} m"
    expect(card).to_contain_text(f"Discrete Fréchet distance{frechet}")
    expect(page.locator("#routes-legend li").nth(1)).to_have_text(
        "B: #{} gravel-loop: Gravel loop (planned)".format(ids["event"])
    )
    shot(page, "routes-planned")

    for screen in ("laptop", "tablet", "phone"):
        page.set_viewport_size(VIEWPORTS[screen]["viewport"])
        assert page.evaluate(OVERFLOWING) == []
        shot(page, f"compare-{screen}")
    page.goto(f"{server.url}/?event={ids['event']}&shift={shift}&leg={by_number[2]}")
    expect(page.locator("#test-case")).to_be_visible()
    assert page.evaluate(OVERFLOWING) == []
    shot(page, "cockpit-phone")
    page.close()
