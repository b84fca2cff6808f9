"""Change history, finalised test events and the frozen taxonomy (issue 26)."""

from datetime import timedelta

import pytest
from django.urls import reverse
from django.utils import timezone

from events.history import authored
from events.models import ItoReason, Segment, Vehicle
from events.selectors.history import history_of
from events.services import finality, logs, segments
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import import_bundle
from reports.selectors.statistics import event_statistics
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.event_writer import write_events
from tests.support.accounts import signed_in, staff_user

# On SpatiaLite too: events/history.py writes history rows in raw SQL.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]


@pytest.fixture
def take_over(leg):
    return segments.report_mode(leg, "ito").master.children.get()


def _assert_reason_entry(segment, channel, author, old="unassigned", new="safety"):
    entries = list(segment.history.order_by("history_id"))
    changed = [
        e for e in entries if e.prev_record and e.ito_reason_id != e.prev_record.ito_reason_id
    ]
    assert len(changed) == 1
    entry = changed[0]
    assert (entry.prev_record.ito_reason_id, entry.ito_reason_id) == (old, new)
    assert entry.history_channel == channel
    assert (entry.history_user.get_username() if entry.history_user else None) == author


def test_reason_changed_through_the_api_names_the_account_and_channel(take_over, api_client):
    client = api_client("operator")
    url = reverse("segment-detail", args=[take_over.pk])
    assert client.patch(url, {"ito_reason": "safety"}, format="json").status_code == 200
    _assert_reason_entry(take_over, "api", client.user.username)
    shown_url = reverse("segment-history", args=[take_over.pk])
    shown = client.get(shown_url).json()
    assert shown[0]["channel"] == "api" and shown[0]["author"] == client.user.username
    change = {"field": "ito_reason", "before": "unassigned", "after": "safety"}
    assert {**change, "field_name": "ito reason"} in shown[0]["changes"]
    assert (shown[0]["kind_text"], shown[0]["channel_text"]) == ("changed", "API")
    german = client.get(shown_url, HTTP_ACCEPT_LANGUAGE="de").json()[0]
    assert {**change, "field_name": "ITO-Grund"} in german["changes"]
    assert (german["kind_text"], german["channel_text"]) == ("geändert", "API")


def test_reason_changed_in_the_gui_is_recorded_as_gui(take_over, client):
    user = signed_in(client, "anna", "operator")
    url = reverse("segment-detail", args=[take_over.pk])
    answer = client.patch(url, {"ito_reason": "safety"}, content_type="application/json")
    assert answer.status_code == 200, answer.content
    _assert_reason_entry(take_over, "gui", user.username)


def test_reason_changed_in_admin_is_recorded_as_admin(take_over, client):
    client.force_login(staff_user("administrator"))
    url = reverse("admin:events_segment_change", args=[take_over.pk])
    data = {"ito_reason": "safety", "obstacle": "", "lighting": "", "slope": ""}
    data.update(initiator="safety_driver", severity="not_applicable", location_type="")
    data.update({f"{p}-{k}": v for p in ("children", "notes") for k, v in _empty_inline().items()})
    assert client.post(url, data).status_code == 302
    _assert_reason_entry(take_over, "admin", "administrator-staff")


def _empty_inline():
    return {"TOTAL_FORMS": "0", "INITIAL_FORMS": "0", "MIN_NUM_FORMS": "0", "MAX_NUM_FORMS": "0"}


def test_reason_changed_by_an_import_is_recorded_as_import(take_over, tmp_path, media_root):
    segments.annotate_segment(take_over, ito_reason="safety")
    logs.close_test_event(take_over.leg.shift.test_event)
    export_events(tmp_path / "a.zip", select_events())
    # An older copy, as another installation held it (a raw write leaves no history).
    stale = timezone.now() - timedelta(days=1)
    Segment.objects.filter(pk=take_over.pk).update(ito_reason="unassigned", annotated=stale)
    with open_archive(tmp_path / "a.zip") as bundle:
        import_bundle(bundle)
    entry = take_over.history.order_by("-history_id").first()
    assert (entry.ito_reason_id, entry.history_channel, entry.history_user) == (
        "safety",
        "import",
        None,
    )


def test_closing_a_master_records_each_child(take_over):
    segments.close_segment(take_over.parent)
    assert take_over.history.filter(end__isnull=False).count() == 1


def test_a_change_of_mode_leaves_one_entry_per_row_it_ends_or_starts(leg):
    robot = staff_user("operator")
    with authored("api", user=robot, reason="field trial"):
        ito = segments.report_mode(leg, "ito", suggested_reason="safety").master
        auto = segments.report_mode(leg, "auto").master
    child = ito.children.get()
    for row in (ito, child):
        created, ended = history_of(row)[::-1]
        assert (created["kind"], ended["kind"]) == ("created", "changed")
        assert {(e["author"], e["channel"], e["reason"]) for e in (created, ended)} == {
            (robot.username, "api", "field trial")
        }
        row.refresh_from_db()
        assert [c for c in ended["changes"] if c["field"] == "end"] == [
            {"field": "end", "field_name": "end", "before": None, "after": str(row.end)}
        ]
    # The robot's suggestion is in the child's first entry, not a change after it.
    assert child.history.earliest("history_id").suggested_reason_id == "safety"
    assert [e["kind"] for e in history_of(auto)] == ["created"]


# --- finalising ------------------------------------------------------------------------------


@pytest.fixture
def final_event(take_over):
    event = logs.close_test_event(take_over.leg.shift.test_event)
    return finality.finalise_test_event(event)


def test_operator_cannot_finalise_or_edit_a_final_event(take_over, api_client):
    event = logs.close_test_event(take_over.leg.shift.test_event)
    operator = api_client("operator")
    refused = operator.post(reverse("test-event-finalise", args=[event.pk]))
    assert refused.status_code == 403
    admin = api_client("administrator")
    assert admin.post(reverse("test-event-finalise", args=[event.pk])).status_code == 200
    url = reverse("segment-detail", args=[take_over.pk])
    answer = operator.patch(url, {"ito_reason": "safety"}, format="json")
    assert answer.status_code == 403
    assert "final" in answer.json()["detail"] and "administrator" in answer.json()["detail"]
    take_over.refresh_from_db()
    assert take_over.ito_reason_id == "unassigned"


def test_administrator_amends_a_final_event_only_with_a_reason(final_event, take_over, api_client):
    admin = api_client("administrator")
    url = reverse("segment-detail", args=[take_over.pk])
    without = admin.patch(url, {"ito_reason": "safety"}, format="json")
    assert without.status_code == 400 and "reason" in without.json()["errors"]
    with_reason = admin.patch(
        url, {"ito_reason": "safety"}, format="json", HTTP_X_FTT_CHANGE_REASON="mis-tapped"
    )
    assert with_reason.status_code == 200
    entry = take_over.history.order_by("-history_id").first()
    assert entry.history_change_reason == "mis-tapped" and entry.ito_reason_id == "safety"


def test_final_event_keeps_its_taxonomy_when_the_catalogue_changes(take_over, other_leg):
    event = take_over.leg.shift.test_event
    segments.annotate_segment(take_over, ito_reason="safety")
    logs.close_test_event(event)
    finality.finalise_test_event(event)
    ItoReason.objects.filter(pk="safety").update(counts_as_intervention=False)
    event.refresh_from_db()
    assert event_statistics(event).overall.interventions == 1
    # An event that is not final follows the catalogue.
    open_event = logs.create_test_event(location="Elsewhere")
    shift = logs.create_shift(test_event=open_event, vehicle=_new_vehicle())
    take = segments.report_mode(logs.create_leg(shift=shift), "ito").master.children.get()
    segments.annotate_segment(take, ito_reason="safety")
    assert event_statistics(open_event).overall.interventions == 0


def _new_vehicle():
    return Vehicle.objects.create(key="moose", short_description="Moose")


def test_the_collector_records_its_mode_changes_as_collector(leg):
    now = timezone.now()
    write_events(
        leg,
        [
            ev.Event(ev.START, now),
            ev.Event(ev.MODE, now, {"mode": "ito", "gps": None, "local": None}),
        ],
    )
    take = Segment.objects.get(leg=leg, parent__isnull=False)
    assert [e.history_channel for e in take.history.all()] == ["collector"]


def test_admin_finalises_and_amends_only_with_a_reason(take_over, client):
    client.force_login(staff_user("administrator"))
    event = logs.close_test_event(take_over.leg.shift.test_event)
    client.post(
        reverse("admin:events_testevent_changelist"),
        {"action": "finalise_selected", "_selected_action": [event.pk]},
    )
    event.refresh_from_db()
    assert event.finalised is not None and event.taxonomy["safety"]["counts"] is True
    url = reverse("admin:events_segment_change", args=[take_over.pk])
    data = {"ito_reason": "safety", "obstacle": "", "lighting": "", "slope": ""}
    data.update(initiator="safety_driver", severity="not_applicable", location_type="")
    data.update({f"{p}-{k}": v for p in ("children", "notes") for k, v in _empty_inline().items()})
    refused = client.post(url, data)
    assert refused.status_code == 200 and "needs a reason" in refused.content.decode()
    assert client.post(url, {**data, "change_reason": "typo"}).status_code == 302
    entry = take_over.history.order_by("-history_id").first()
    assert (entry.ito_reason_id, entry.history_change_reason) == ("safety", "typo")
