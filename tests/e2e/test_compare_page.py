"""The comparison page: pick test events, see their reliability side by side with
the same figures as the API, get the comparison PDF; on a laptop, a tablet and a
phone, with nothing scrolling sideways and every target big enough to tap."""

import json

import pytest
from playwright.sync_api import expect

from tests.support.browser import login
from tests.support.pdf import flat, has_row, pdf_text, save_pages
from tests.support.screens import OVERFLOWING, SMALL, VIEWPORTS

TARGETS = (
    "#event-list label, #compare-run, #compare-pdf, #compare-mode, #hotspots a, a.download, "
    ".topbar nav a, .topbar nav button"
)


@pytest.fixture(scope="module")
def two_events(server):
    """Two test events of one vehicle with different software versions; in each an
    AUTO run, a take-over for a counted reason at the same place, and AUTO again.
    The second event's AUTO run lies about 5.6 m north of the first's (5e-5°)."""
    out = server.python(
        """
        import json
        from datetime import UTC, datetime, timedelta
        from events.models import Vehicle
        from events.services import logs, segments
        from events.services.segments import GpsPosition
        from telemetry.services import pose_writes
        vehicle = Vehicle.objects.create(key="compare-rover", short_description="Compare Rover")
        ids = []
        for n, version in enumerate(("1.0 Ölberg", "2.0")):
            t0 = datetime(2026, 4, 1 + n, 8, 0, tzinfo=UTC)
            at = lambda s: t0 + timedelta(seconds=s)
            e = logs.create_test_event(
                location=f"Compare field {n + 1}", version=version, time_zone="UTC", at=t0
            )
            s = logs.create_shift(test_event=e, vehicle=vehicle, at=t0)
            leg = logs.create_leg(shift=s, at=t0, weather_id="sunny")
            auto = segments.report_mode(leg, "auto", at=at(0), gps=GpsPosition(7.0, 50.0)).master
            pose_writes.store_poses(
                auto,
                [
                    pose_writes.GpsFix(7.0 + i * 1e-4, 50.0 + n * 5e-5, robot_stamp=at(i))
                    for i in range(1, 30)
                ],
            )
            ito = segments.report_mode(
                leg, "ito", at=at(60), gps=GpsPosition(7.003, 50.0), reason="safety"
            ).master
            segments.report_mode(leg, "auto", at=at(90), gps=GpsPosition(7.0031, 50.0))
            logs.close_leg(leg, at=at(200))
            logs.close_shift(s, at=at(200))
            ids.append({"event": e.pk, "shift": s.pk, "leg": leg.pk, "ito": ito.pk})
        print(json.dumps(ids))
        """
    )
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("screen", list(VIEWPORTS))
def test_comparison_page_fits_and_matches_the_api(browser, server, two_events, shot, screen):
    page = browser.new_page(**VIEWPORTS[screen])
    login(page, server, "otto")
    first, second = (e["event"] for e in two_events)
    page.goto(f"{server.url}/compare/")
    page.get_by_label(f"#{first} Compare field 1", exact=False).check()
    page.get_by_label(f"#{second} Compare field 2", exact=False).check()
    page.get_by_role("button", name="Compare", exact=True).click()
    cards = page.locator("#by-event article")
    expect(cards).to_have_count(2)
    # The page shows what the API says, in the PDF's wording.
    query = f"test_event={first}&test_event={second}"
    api = page.request.get(f"{server.url}/api/reports/compare/?{query}").json()
    for card, group in zip(cards.all(), api["test_events"], strict=True):
        shown = group["shown"]
        for label, key in (
            ("MDBI", "mdbi"),
            ("MDBI 90 % bounds", "mdbi_bounds"),
            ("MTBI 90 % bounds", "mtbi_bounds"),
            ("Interventions per km", "per_km"),
            ("Interventions per hour", "per_hour"),
        ):
            value = card.locator(f"dt:text-is('{label}') + dd")
            expect(value).to_have_text(shown[key])
        expect(card.locator("dt:text-is('Interventions') + dd")).to_have_text("1")
    expect(page.locator("#by-version article h3")).to_have_text(["1.0 Ölberg", "2.0"])
    # Both take-overs happened at the same place: one hotspot linking to both segments.
    expect(page.locator("#hotspots > li")).to_have_count(1)
    links = page.locator("#hotspots a")
    expect(links).to_have_count(2)
    ito = two_events[0]
    expect(links.first).to_have_attribute(
        "href",
        f"/?event={ito['event']}&shift={ito['shift']}&leg={ito['leg']}&segment={ito['ito']}",
    )
    shot(page, f"{screen}-comparison")
    assert page.evaluate(OVERFLOWING) == []
    assert page.evaluate(SMALL, TARGETS) == []
    page.close()


def test_comparison_pdf_is_made_and_survives_a_reload(browser, server, two_events, shot, tmp_path):
    page = browser.new_page(**VIEWPORTS["tablet"])
    login(page, server, "otto")
    first, second = (e["event"] for e in two_events)
    page.goto(f"{server.url}/compare/?event={first}&event={second}&mode=gps")
    # The address keeps the choice: the comparison is shown straight away.
    expect(page.locator("#by-event article")).to_have_count(2)
    # The two events' legs compared as routes: the PDF gets what the screen shows.
    legs = [e["leg"] for e in two_events]
    routes = page.locator("#routes-form")
    routes.get_by_label("First leg").select_option(str(legs[0]))
    routes.get_by_label("Second route").select_option(str(legs[1]))
    routes.get_by_label("Threshold (m)").fill("3")
    page.get_by_role("button", name="Compare routes").click()
    expect(page.locator("#routes-status")).to_have_text("Routes compared; threshold 3 m.")
    answer = page.request.get(
        f"{server.url}/api/reports/routes/?leg={legs[0]}&leg={legs[1]}&threshold=3"
    ).json()
    pair = answer["pairs"][0]
    expect(page.locator("#routes-figures article")).to_contain_text(
        f"Discrete Fréchet distance{pair['frechet']:.1f} m"
    )
    # A threshold typed but not compared is not what the screen shows: not in the PDF.
    routes.get_by_label("Threshold (m)").fill("50")
    page.get_by_role("button", name="Make PDF").click()
    download = page.locator("#compare-status a.download")
    expect(download).to_be_visible(timeout=180_000)
    shot(page, "pdf-ready")
    page.reload()
    # After a reload the finished job's link is there again, without asking anew.
    expect(page.locator("#compare-status a.download")).to_be_visible(timeout=30_000)
    href = page.locator("#compare-status a.download").get_attribute("href")
    response = page.request.get(href)
    assert response.status == 200
    assert response.body()[:5] == b"%PDF-"
    assert "ftt-comparison-" in response.headers["content-disposition"]
    save_pages(response.body(), "compare-page-routes")
    text = pdf_text(response.body(), tmp_path)
    assert "Routes" in text and "more than 3.00 m" in flat(text), text
    for letter, colour, event in (("A", "blue", first), ("B", "orange", second)):
        assert has_row(text, letter, colour, f"Test event {event}, shift 1, leg 1"), text
    for name, other, leg in (("A", "B", legs[0]), ("B", "A", legs[1])):
        side = pair["deviation"][f"leg {leg}"]
        figures = [f"{pair['frechet']:.2f} m"]
        figures += [f"{side[key]:.2f} m" for key in ("mean", "p95", "max")]
        assert side["share_beyond"] > 0.5  # the 5.6 m apart are beyond 3 m
        share = f"{100 * side['share_beyond']:.1f} %"
        assert has_row(text, f"{name} from {other}", *figures, share), text
    page.close()


def test_a_viewer_sees_the_figures_but_cannot_make_a_pdf(browser, server, two_events):
    page = browser.new_page(**VIEWPORTS["phone"])
    login(page, server, "vera")
    first, second = (e["event"] for e in two_events)
    page.goto(f"{server.url}/compare/?event={first}&event={second}")
    expect(page.locator("#by-event article")).to_have_count(2)
    expect(page.get_by_role("button", name="Make PDF")).to_be_disabled()
    page.close()


def test_a_test_case_title_in_a_route_tooltip_is_shown_as_text(browser, server, two_events):
    """A planned route's tooltip names its test case: a title holding HTML is
    shown as written, never parsed (issue 48 finding 12)."""
    first = two_events[0]
    title = '<img src="/static/gui/favicon.svg" id="planted"><b>Bold loop</b>'
    case = server.python(
        f"""
        from django.contrib.gis.geos import LineString
        from events.models import TestCase
        case = TestCase.objects.create(
            test_event_id={first["event"]}, key="html-title", title={title!r}, planned_runs=1,
            route=LineString((7.0001, 50.0), (7.0029, 50.0), srid=4326),
        )
        print(case.pk)
        """
    )
    case = int(case.strip().splitlines()[-1])
    page = browser.new_page(**VIEWPORTS["laptop"])
    login(page, server, "otto")
    page.goto(f"{server.url}/compare/")
    routes = page.locator("#routes-form")
    routes.get_by_label("First leg").select_option(str(first["leg"]))
    routes.get_by_label("Second route").select_option(f"case:{case}")
    routes.get_by_label("Threshold (m)").fill("50")
    page.get_by_role("button", name="Compare routes").click()
    expect(page.locator("#routes-status")).to_have_text("Routes compared; threshold 50 m.")
    # The planned route (B, drawn last and on top) is a straight line: its middle is on it.
    line = page.locator("#routes-map path").nth(1)
    page.locator("#routes-map").evaluate("(map) => map.scrollIntoView({block: 'center'})")
    box = line.bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2, steps=5)
    tooltip = page.locator("#routes-map .leaflet-tooltip")
    expect(tooltip).to_contain_text(f"B: #{first['event']} html-title: {title} (planned)")
    expect(tooltip.locator("b, img")).to_have_count(0)
    expect(page.locator("#planted")).to_have_count(0)
    page.close()
