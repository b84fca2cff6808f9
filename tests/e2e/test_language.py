"""A German browser gets the cockpit in German: the page, its scripts' words
(Django's JavaScript catalogue) and dates written the German way."""

import re

import pytest
from playwright.sync_api import expect

from tests.support.browser import PASSWORD, choose_event, german_page, login

pytestmark = pytest.mark.e2e


def test_a_german_browser_gets_the_cockpit_in_german(browser, server, open_leg):
    with german_page(browser, server) as page:
        choose_event(page, open_leg)
        expect(page.locator("html")).to_have_attribute("lang", "de")
        expect(page.get_by_role("button", name="Abmelden")).to_be_visible()
        # Written by the script: its words from /jsi18n/, the date by Intl in German.
        event = page.locator("#pick-event option", has_text=f"Gelände {open_leg}")
        expect(event).to_have_text(re.compile(r" · \d{1,2}\.\d{1,2}\.\d{4} · offen$"))
        expect(page.locator("#pick-shift option:checked")).to_have_text(
            re.compile(r"^Schicht 1 · ")
        )


# The choice is kept on the account, so this test signs in as a viewer of its
# own: the shared accounts keep the language every other test reads.
LOTTE = f"""
from django.contrib.auth.models import Group, User
u = User.objects.create_user("lotte", password={PASSWORD!r})
u.groups.add(Group.objects.get(name="viewer"))
"""


def test_the_cockpits_top_bar_has_the_language_picker(browser, server, open_leg):
    server.python(LOTTE)
    context = browser.new_context(locale="en-GB")
    try:
        page = context.new_page()
        login(page, server, "lotte")
        choose_event(page, open_leg)
        picker = page.locator(".topbar").get_by_label("Language")
        expect(picker).to_be_visible()
        expect(page.locator(".topbar .language-apply")).to_be_hidden()
        picker.select_option("de")
        expect(page.locator("html")).to_have_attribute("lang", "de")
        expect(page.get_by_role("button", name="Abmelden")).to_be_visible()
        # Kept on the account: the choice outlives the page it was made on.
        picker = page.locator(".topbar").get_by_label("Sprache")
        expect(picker).to_have_value("de")
        # The new page sends the picker on a change only once its deferred script
        # has run, which hides the button a page without script needs.
        expect(page.locator(".topbar .language-apply")).to_be_hidden()
        picker.select_option("en")
        expect(page.get_by_role("button", name="Sign out")).to_be_visible()
    finally:
        context.close()
