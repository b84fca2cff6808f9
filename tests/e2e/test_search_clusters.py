"""Where did it fail, at a few thousand take-overs: the comparison page's search map
groups them into clusters with their count (Leaflet.markercluster), on the laptop,
the tablet and the phone."""

import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import login, open_leg_code
from tests.support.screens import OVERFLOWING, VIEWPORTS

pytestmark = pytest.mark.e2e

TAKE_OVERS = 3000

# Closed take-overs, ten seconds apart, scattered over a 4 km square near Wachtberg.
MANY = """
import random, uuid
from datetime import timedelta
from django.contrib.gis.geos import Point
from events.models import Leg, Segment, SegmentType
leg = Leg.objects.get(shift__vehicle__key="{key}")
rng = random.Random(29)
Segment.objects.bulk_create(
    Segment(
        leg=leg, segment_type_id=SegmentType.ITO, uid=uuid.uuid4(),
        start=leg.start + timedelta(seconds=10 * i), end=leg.start + timedelta(seconds=10 * i + 5),
        start_position=Point(7.1 + rng.random() * 0.05, 50.6 + rng.random() * 0.035, srid=4326),
    )
    for i in range({count})
)
print(leg.shift.test_event_id)
"""

CLUSTER_COUNTS = """() => Array.from(document.querySelectorAll("#search-map .marker-cluster"))
  .map((el) => Number(el.textContent))"""


def test_thousands_of_take_overs_are_clustered_with_their_count(browser, server, shot):
    key = "cluster-rover"
    server.python(open_leg_code(key))
    event = server.python(MANY.format(key=key, count=TAKE_OVERS)).strip().splitlines()[-1]
    page = browser.new_page(**VIEWPORTS["laptop"])
    login(page, server, "vera")
    page.goto(f"{server.url}/compare/")
    page.locator("#search-form").get_by_label("Test event").select_option(event)
    page.get_by_role("button", name="Search", exact=True).click()
    expect(page.locator("#search-status")).to_have_text(
        re.compile(rf"^{TAKE_OVERS} take-overs found\.")
    )
    clusters = page.locator("#search-map .marker-cluster")
    expect(clusters.first).to_be_visible()
    # The map is framed on what was found: once the zoom has settled, every
    # take-over is in exactly one cluster (while it animates, the clusters of
    # both zoom levels are on the page).
    page.wait_for_function(
        f"() => ({CLUSTER_COUNTS})().reduce((sum, n) => sum + n, 0) === {TAKE_OVERS}"
    )
    assert clusters.count() < 100
    shot(page, "clusters-laptop")
    for screen in ("tablet", "phone"):
        page.set_viewport_size(VIEWPORTS[screen]["viewport"])
        page.locator("#search-map").scroll_into_view_if_needed()
        expect(clusters.first).to_be_visible()
        assert page.evaluate(OVERFLOWING) == []
        shot(page, f"clusters-{screen}")
    # A cluster tapped opens: the map zooms in and its take-overs split up.
    largest = max(page.evaluate(CLUSTER_COUNTS))
    clusters.filter(has_text=re.compile(rf"^{largest}$")).first.click()
    page.wait_for_function(
        f"() => Math.max(...Array.from(document.querySelectorAll('#search-map .marker-cluster'))"
        f".map((el) => Number(el.textContent))) < {largest}"
    )
    shot(page, "cluster-opened")
    page.close()
