"""A final, amended test event in the GUI; a report checked in the reports dialog (issue 26)."""

from playwright.sync_api import expect

from tests.support.browser import choose_event, login

FINALISE_AND_AMEND = """
from django.contrib.auth.models import User
from events.history import authored
from events.models import TestEvent
from events.services import finality, logs, segments
from reports.selectors.provenance import json_report
e = TestEvent.objects.get(location="Gelände {key}")
take_over = segments.new_manual_segment(e.shifts.get().legs.get())
e = finality.finalise_test_event(logs.close_test_event(e))
with authored("admin", user=User.objects.get(username="ada"), reason="mis-tapped"):
    segments.annotate_segment(take_over, ito_reason="other")
print("REPORT" + json_report(e, "gps"))
"""

AMEND_AGAIN = """
from django.contrib.auth.models import User
from events.history import authored
from events.models import Segment
from events.services import segments
e = "Gelände {key}"
take_over = Segment.objects.get(leg__shift__test_event__location=e, parent__isnull=False)
with authored("admin", user=User.objects.get(username="ada"), reason="weather"):
    segments.annotate_segment(take_over, obstacle="fog")
"""


def _verify(page, report: bytes):
    dialog = page.locator("#reports-dialog")
    form = dialog.locator("#verify-form")
    form.get_by_label("Report file (PDF or JSON)").set_input_files(
        {"name": "figures.json", "mimeType": "application/json", "buffer": report}
    )
    form.get_by_role("button", name="Verify").click()
    return form.locator(".verify-answer")


def test_final_event_shows_its_amendments_and_a_report_is_verified(page, server, open_leg, shot):
    out = server.python(FINALISE_AND_AMEND.format(key=open_leg))
    report = out.split("REPORT", 1)[1].strip().encode()
    login(page, server, "otto")
    choose_event(page, open_leg)
    expect(page.locator('[data-state="event"]')).to_have_text("final, amended 1 time")
    # Closed but final: the page shows Re-open only where the server says it may.
    expect(page.locator('[data-action="reopen"][data-level="event"]')).to_be_hidden()
    page.get_by_role("button", name="Reports & exports").click()
    answer = _verify(page, report)
    expect(answer).to_contain_text("OK: The data of test event")
    shot(page, "report-verified")
    server.python(AMEND_AGAIN.format(key=open_leg))
    answer = _verify(page, report)
    expect(answer).to_contain_text("CHANGED: The data of test event")
    expect(answer.locator("li")).to_contain_text("changed")
    expect(answer.locator("li")).to_contain_text("by ada via admin (weather)")
    shot(page, "report-changed")
    # A file that is no report is refused in words, next to its field.
    page.locator("#verify-form input[type=file]").set_input_files(
        {"name": "notes.txt", "mimeType": "text/plain", "buffer": b"just notes"}
    )
    page.locator("#verify-form").get_by_role("button", name="Verify").click()
    expect(page.locator("#reports-dialog")).to_contain_text("no FTT data digest")
    page.get_by_role("button", name="Close").last.click()
    page.reload()
    expect(page.locator('[data-state="event"]')).to_have_text("final, amended 2 times")
