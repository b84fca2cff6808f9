"""The cockpit's segment writes answer with every row the change touched, as the
REST list shows them, so the page redraws without reading the list again; the
rules, roles and refusals are the segment rules' own, as the REST actions answer them."""

import uuid
from datetime import timedelta

import pytest
from django.utils import timezone

from events.models import Leg, Segment, SegmentType, Shift, TestEvent
from events.services import segments
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db


def by_id(rows):
    return {r["id"]: r for r in rows}


def listed(client, leg):
    return by_id(client.get(f"/gui/api/legs/{leg.pk}/segments/").json()["segments"])


def test_a_take_over_in_auto_answers_the_closed_auto_and_the_new_ito_rows(api_client, leg):
    auto = start_auto(leg)
    client = api_client("operator")
    answer = client.post(f"/gui/api/legs/{leg.pk}/manual-segment/", {}, format="json")
    assert answer.status_code == 201, answer.content
    body = answer.json()
    reason = Segment.objects.get(pk=body["segment"]["id"])
    master = reason.parent
    rows = by_id(body["segments"])
    assert set(rows) == {auto.pk, master.pk, reason.pk}
    # Each row as the list now shows it: the AUTO closed where the take-over began.
    now = listed(client, leg)
    assert all(rows[pk] == now[pk] for pk in rows)
    assert rows[auto.pk]["is_open"] is False and rows[auto.pk]["end"] == rows[master.pk]["start"]
    assert rows[reason.pk]["segment_type"] == "ito" and rows[reason.pk]["is_open"] is True
    labels = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["labels"]
    assert body["labels"] == {str(pk): labels[str(pk)] for pk in rows}
    assert body["labels"][str(reason.pk)] == f"Leg {leg.number} · #2.1"
    assert body["short_labels"][str(reason.pk)] == "#2.1"
    assert body["open_take_over"] == reason.pk


def test_a_take_over_in_ito_answers_its_new_reason_under_the_open_master(api_client, leg):
    first = segments.new_manual_segment(leg)
    client = api_client("operator")
    body = client.post(f"/gui/api/legs/{leg.pk}/manual-segment/", {}, format="json").json()
    rows = by_id(body["segments"])
    assert body["segment"]["parent"] == first.parent_id
    assert {body["segment"]["id"], first.parent_id} <= set(rows)
    now = listed(client, leg)
    assert rows == {pk: now[pk] for pk in rows}


def test_ending_a_master_answers_its_reasons_closed_too(api_client, leg):
    reason = segments.new_manual_segment(leg)
    client = api_client("operator")
    answer = client.post(f"/gui/api/segments/{reason.parent_id}/close/", {}, format="json")
    assert answer.status_code == 200, answer.content
    body = answer.json()
    rows = by_id(body["segments"])
    assert body["segment"]["id"] == reason.parent_id
    assert {reason.pk, reason.parent_id} <= set(rows)
    assert not rows[reason.pk]["is_open"] and not rows[reason.parent_id]["is_open"]
    assert rows == {pk: row for pk, row in listed(client, leg).items() if pk in rows}


def test_refusals_are_the_rest_actions_and_write_nothing(api_client, leg):
    reason = segments.new_manual_segment(leg)
    segments.close_segment(reason)
    client = api_client("operator")
    close = f"segments/{reason.pk}/close/"
    again = client.post(f"/gui/api/{close}", {}, format="json")
    assert again.status_code == 409
    assert again.json() == client.post(f"/api/{close}", {}, format="json").json()
    viewer = api_client("viewer")
    count = Segment.objects.count()
    refused = viewer.post(f"/gui/api/legs/{leg.pk}/manual-segment/", {}, format="json")
    assert refused.status_code == 403
    new = f"/gui/api/legs/{leg.pk}/manual-segment/"
    wrong = client.post(new, {"reason": "nope"}, format="json")
    assert wrong.status_code == 400 and "reason" in wrong.json()["errors"]
    assert client.post("/gui/api/segments/999999/close/", {}, format="json").status_code == 404
    assert Segment.objects.count() == count


def test_a_quick_reason_annotates_the_open_take_over_whichever_is_selected(api_client, leg):
    older = segments.new_manual_segment(leg)
    segments.report_mode(leg, SegmentType.AUTO)
    newer = segments.report_mode(leg, SegmentType.ITO).master.children.get()
    client = api_client("operator")
    answer = client.post(
        f"/gui/api/legs/{leg.pk}/quick-reason/", {"reason": "safety"}, format="json"
    )
    assert answer.status_code == 200, answer.content
    body = answer.json()
    assert body["segment"]["id"] == newer.pk == body["open_take_over"]
    assert body["segment"]["ito_reason"] == "safety"
    assert body["short_labels"][str(newer.pk)] == "#3.1"
    older.refresh_from_db()
    assert older.ito_reason_id == "unassigned"
    assert listed(client, leg)[newer.pk] == body["segment"]


def test_a_quick_reason_without_an_open_take_over_is_refused_with_a_message(api_client, leg):
    segments.report_mode(leg, SegmentType.AUTO)
    client = api_client("operator")
    url = f"/gui/api/legs/{leg.pk}/quick-reason/"
    refused = client.post(url, {"reason": "safety"}, format="json")
    assert refused.status_code == 409
    assert "No take-over is open" in refused.json()["detail"]
    missing = client.post(url, {}, format="json")
    assert missing.status_code == 400 and "reason" in missing.json()["errors"]
    assert api_client("viewer").post(url, {"reason": "safety"}, format="json").status_code == 403
    assert client.get(f"/gui/api/legs/{leg.pk}/segments/").json()["open_take_over"] is None


def test_writes_kept_offline_are_stored_once_and_land_where_the_operator_tapped(api_client, leg):
    """A page that kept writes on a dead link sends them again until it hears an
    answer: a take-over under its uid is stored once, and a quick reason goes to
    the take-over the operator saw, though another is open by the time it arrives."""
    client = api_client("operator")
    url = f"/gui/api/legs/{leg.pk}/manual-segment/"
    uid = "6f1c3b1e-1b7a-4c55-9a51-2a0d6f1e2b3c"
    first = client.post(url, {"uid": uid}, format="json")
    again = client.post(url, {"uid": uid}, format="json")
    assert first.status_code == 201 and again.status_code == 201, again.content
    assert again.json()["segment"]["id"] == first.json()["segment"]["id"]
    assert Segment.objects.filter(leg=leg, parent__isnull=False).count() == 1
    seen = Segment.objects.get(uid=uid)
    segments.report_mode(leg, SegmentType.AUTO)
    newer = segments.report_mode(leg, SegmentType.ITO).master.children.get()
    reason = f"/gui/api/legs/{leg.pk}/quick-reason/"
    kept = {"reason": "safety", "take_over": seen.pk}
    for _ in range(2):
        answer = client.post(reason, kept, format="json")
        assert answer.status_code == 200, answer.content
        assert answer.json()["segment"]["id"] == seen.pk
    seen.refresh_from_db()
    newer.refresh_from_db()
    assert (seen.ito_reason_id, newer.ito_reason_id) == ("safety", "unassigned")
    # The take-over was deleted meanwhile: the page is told why in words.
    gone = client.post(reason, {"reason": "safety", "take_over": 999999}, format="json")
    assert gone.status_code == 404
    assert "no longer exists" in gone.json()["detail"]


def test_a_take_over_kept_offline_starts_when_it_was_tapped(api_client, leg):
    """The page says how long ago, by its own clock: the take-over is not dated
    to the moment the link came back, and a wrong tablet date does not matter."""
    client = api_client("operator")
    earlier = timezone.now() - timedelta(minutes=10)
    TestEvent.objects.filter(pk=leg.shift.test_event_id).update(start=earlier)
    Shift.objects.filter(pk=leg.shift_id).update(start=earlier)
    Leg.objects.filter(pk=leg.pk).update(start=earlier)
    leg.refresh_from_db()
    segments.report_mode(leg, SegmentType.AUTO, at=timezone.now() - timedelta(minutes=5))
    url = f"/gui/api/legs/{leg.pk}/manual-segment/"
    before = timezone.now()
    answer = client.post(url, {"uid": str(uuid.uuid4()), "seconds_ago": 42.5}, format="json")
    assert answer.status_code == 201, answer.content
    child = Segment.objects.get(pk=answer.json()["segment"]["id"])
    assert abs((before - child.start).total_seconds() - 42.5) < 2.0
    assert child.parent.start == child.start  # the switch to ITO happened then too
    # Before the open AUTO run began, it cannot have happened: said, not stored.
    late = client.post(url, {"uid": str(uuid.uuid4()), "seconds_ago": 3600}, format="json")
    assert late.status_code == 409 and Segment.objects.filter(leg=leg).count() == 3
    refused = client.post(url, {"seconds_ago": -1}, format="json")
    assert refused.status_code == 400 and "seconds_ago" in refused.json()["errors"]
