"""The cockpit as a German browser shows it, the words its scripts write
included (segment rows, the pickers, the who-line): none of FTT's own English
words (tests/support/english.py)."""

import json
import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import german_page
from tests.support.english import english_in

pytestmark = pytest.mark.e2e

TAKE_OVER = """
import json
from events.models import Vehicle
from events.services import logs, segments
v = Vehicle.objects.create(key="kran", short_description="Kran")
e = logs.create_test_event(location="Kiesgrube", time_zone="Europe/Berlin")
leg = logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v), weather_id="sunny")
segments.report_mode(leg, "auto")
segments.report_mode(leg, "ito", reason="planner")
print(json.dumps({"event": e.pk, "shift": leg.shift_id, "leg": leg.pk}))
"""


def test_the_german_cockpit_shows_no_english(browser, server):
    chosen = json.loads(server.python(TAKE_OVER).strip().splitlines()[-1])
    with german_page(browser, server) as page:
        page.goto(f"{server.url}/?{'&'.join(f'{k}={v}' for k, v in chosen.items())}")
        rows = page.locator("#segment-table tbody tr")
        expect(rows).to_have_count(2)  # AUTO, then the take-over
        expect(page.locator("html")).to_have_attribute("lang", "de")
        # Names people gave (this test's and other tests' on the shared server)
        # are theirs, not FTT's words.
        named = stored_names(server)
        assert english_in(without(shown_words(page), named)) == []
        assert "geschlossen" in shown_words(page) and "offen" in shown_words(page)
        # The take-over ends live: the rows that arrive by the live feed speak German too.
        expect(page.locator("#live-status")).to_have_attribute("data-state", "ok", timeout=15_000)
        server.python(LIVE_END.format(leg=chosen["leg"]))
        expect(rows).to_have_count(3)
        expect(rows.first.locator("td").first).to_have_attribute(
            "title", re.compile(r"^Etappe 1 · #3 ")
        )
        assert english_in(without(shown_words(page), named)) == []


LIVE_END = """
from events.models import Leg
from events.services import segments
segments.report_mode(Leg.objects.get(pk={leg}), "auto")
"""


STORED_NAMES = """
import json
from events.models import TestEvent, Vehicle
names = [*Vehicle.objects.values_list("short_description", flat=True)]
names += TestEvent.objects.values_list("location", flat=True)
print(json.dumps(names))
"""


def stored_names(server) -> list[str]:
    """The vehicles' and test events' names in the server's database."""
    return json.loads(server.python(STORED_NAMES).strip().splitlines()[-1])


def without(text: str, names: list[str]) -> str:
    """``text`` with each whole name taken out (a word of FTT's beside one stays)."""
    for name in sorted(filter(None, names), key=len, reverse=True):
        text = text.replace(name, " ")
    return text


def shown_words(page) -> str:
    """The page's text with its titles, labels, placeholders and options."""
    return page.evaluate(
        # Leaflet's own controls (zoom, its attribution) speak Leaflet's words.
        """() => {
                const own = document.querySelectorAll(".leaflet-control-container");
                for (const control of own) control.remove();
                return [document.body.innerText, ...[...document.querySelectorAll(
                    "[title], [aria-label], [placeholder], option")].map((e) =>
                    [e.title, e.getAttribute("aria-label"), e.placeholder, e.textContent].join(" "))
                ].join(" ");
            }"""
    )


OFFLINE_ROBOT = """
from datetime import timedelta
from django.utils import timezone
from events.models import Vehicle
from events.services import logs, segments
from rosbridge_app.models import Collector
from rosbridge_app.services import collectors
v = Vehicle.objects.create(key="bagger", short_description="Bagger")
e = logs.create_test_event(location="Tagebau", time_zone="Europe/Berlin")
leg = logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v), weather_id="sunny")
segments.report_mode(leg, "auto")
collectors.heartbeat("bagger-collector", vehicle=v, logging=True, leg=leg)
# Heard a minute ago: logging, but offline, and no position sent yet.
heard = timezone.now() - timedelta(minutes=1)
Collector.objects.filter(name="bagger-collector").update(last_seen=heard)
"""


def test_the_german_fleet_lists_a_robot_without_position_and_offline_in_german(browser, server):
    server.python(OFFLINE_ROBOT)
    with german_page(browser, server) as page:
        page.goto(f"{server.url}/?view=fleet")
        robot = page.locator(".fleet-vehicle", has_text="Bagger")
        expect(robot).to_be_visible()
        words = robot.evaluate("(b) => [b.innerText, b.title].join(' ')")
        assert english_in(without(words, stored_names(server))) == []
