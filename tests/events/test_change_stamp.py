"""Every change to a log entry or segment moves its change stamp, whoever makes it.

The import's "later change wins" rule reads this stamp, so a change that did
not move it would be undone by the next stale archive.
"""

import pytest
from django.urls import reverse

from events.models import Segment, Shift
from events.services import logs, segments
from tests.support.accounts import staff_user


def _stamp(row):
    return type(row).objects.values_list("modified", flat=True).get(pk=row.pk)


def test_a_service_edit_moves_the_stamp_of_that_row_only(shift, leg):
    shift_before, leg_before = _stamp(shift), _stamp(leg)
    logs.update_shift(shift, workspace="north meadow")
    assert _stamp(shift) > shift_before
    assert _stamp(leg) == leg_before


def test_closing_a_master_moves_the_stamps_of_the_children_it_closes(leg):
    master = segments.report_mode(leg, "ito").master
    child = master.children.get()
    before = _stamp(child)
    segments.close_segment(master)
    assert Segment.objects.get(pk=child.pk).end is not None
    assert _stamp(child) > before


def test_annotating_a_reason_moves_its_stamp(leg):
    child = segments.report_mode(leg, "ito").master.children.get()
    before = _stamp(child)
    segments.annotate_segment(child, ito_reason="safety")
    assert _stamp(child) > before


@pytest.mark.django_db
def test_an_edit_in_admin_moves_the_stamp_and_the_page_shows_it(client, shift):
    client.force_login(staff_user("administrator"))
    url = reverse("admin:events_shift_change", args=[shift.pk])
    page = client.get(url)
    assert b"Modified" in page.content
    before = _stamp(shift)
    form = {
        "vehicle": shift.vehicle_id,
        "performer": shift.performer_id or "",
        "test_intent": "night run",
        "workspace": shift.workspace,
        "note": shift.note,
        **{
            f"{role}": getattr(shift, f"{role}_id") or ""
            for role in (
                "test_administrator",
                "test_director",
                "safety_officer",
                "robot_operator",
            )
        },
        "legs-TOTAL_FORMS": "0",
        "legs-INITIAL_FORMS": "0",
    }
    response = client.post(url, form)
    assert response.status_code == 302, response.content.decode()[:2000]
    assert Shift.objects.get(pk=shift.pk).test_intent == "night run"
    assert _stamp(shift) > before
