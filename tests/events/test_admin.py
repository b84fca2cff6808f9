"""Django admin is the configuration UI; it must work offline and respect roles."""

from html.parser import HTMLParser

import pytest
from django.urls import reverse

from events.models import ItoReason, Segment, SegmentType
from events.services import segments
from tests.support.accounts import staff_user
from tests.support.pages import external_assets


@pytest.fixture
def admin_client(client, db):
    client.force_login(staff_user("administrator"))
    return client


def test_every_changelist_and_add_page_renders(admin_client):
    for name in [
        "personnel",
        "performer",
        "vehicle",
        "posesource",
        "weather",
        "itoreason",
        "segmenttype",
        "testevent",
        "shift",
        "leg",
        "segment",
        "note",
    ]:
        url = reverse(f"admin:events_{name}_changelist")
        assert admin_client.get(url).status_code == 200, url
    for name in ["pose", "localpose", "mapimage", "image"]:
        assert admin_client.get(reverse(f"admin:telemetry_{name}_changelist")).status_code == 200


def test_hierarchy_pages_link_up_and_down_and_load_no_external_assets(admin_client, leg):
    master = segments.report_mode(leg, "ito").master
    child = master.children.get()
    page = admin_client.get(reverse("admin:events_segment_change", args=[child.pk]))
    html = page.content.decode()
    assert page.status_code == 200
    assert reverse("admin:events_leg_change", args=[leg.pk]) in html
    assert reverse("admin:events_segment_change", args=[master.pk]) in html
    assert external_assets(html) == []
    leg_page = admin_client.get(reverse("admin:events_leg_change", args=[leg.pk])).content.decode()
    assert reverse("admin:events_segment_change", args=[master.pk]) in leg_page
    assert reverse("admin:events_shift_change", args=[leg.shift.pk]) in leg_page


def test_catalogues_are_read_only_for_operators(client, db):
    client.force_login(staff_user("operator"))
    url = reverse("admin:events_itoreason_change", args=["safety"])
    page = client.get(url)
    assert page.status_code == 200
    assert b'name="short_description"' not in page.content
    response = client.post(url, {"short_description": "Hacked", "color": "1,1,1"})
    assert response.status_code == 403
    assert ItoReason.objects.get(pk="safety").short_description == "Safety"


def test_administrator_edits_a_catalogue(admin_client):
    url = reverse("admin:events_itoreason_change", args=["other"])
    data = {
        "short_description": "Sonstiges",
        "long_description": "Andere Gründe.",
        "color": "180,180,180",
        "counts_as_intervention": "on",
    }
    assert admin_client.post(url, data).status_code == 302
    assert ItoReason.objects.get(pk="other").short_description == "Sonstiges"


def test_admin_action_ends_a_test_event_through_the_service(admin_client, leg):
    segments.report_mode(leg, "auto")
    event = leg.shift.test_event
    admin_client.post(
        reverse("admin:events_testevent_changelist"),
        {"action": "close_selected", "_selected_action": [event.pk]},
    )
    assert not Segment.objects.filter(end__isnull=True).exists()
    event.refresh_from_db()
    assert event.end is not None


def test_deleting_a_vehicle_in_use_is_refused_with_where_it_is_used(admin_client, shift):
    url = reverse("admin:events_vehicle_delete", args=[shift.vehicle.pk])
    response = admin_client.post(url, {"post": "yes"}, follow=True)
    assert type(shift.vehicle).objects.filter(pk=shift.vehicle.pk).exists()
    assert "Shift 1" in response.content.decode()


def test_recorded_data_is_read_only(admin_client):
    page = admin_client.get(reverse("admin:telemetry_pose_add"))
    assert page.status_code == 403


def test_keys_the_rules_need_cannot_be_deleted_from_admin(admin_client):
    page = admin_client.get(reverse("admin:events_itoreason_change", args=["unassigned"]))
    delete_url = reverse("admin:events_itoreason_delete", args=["unassigned"])
    assert delete_url not in page.content.decode()
    assert admin_client.post(delete_url, {"post": "yes"}).status_code == 403
    response = admin_client.post(
        reverse("admin:events_segmenttype_changelist"),
        {
            "action": "delete_selected",
            "_selected_action": ["ito", "auto", "unknown"],
            "post": "yes",
        },
    )
    assert response.status_code == 403
    assert set(SegmentType.objects.values_list("key", flat=True)) == {"ito", "auto", "unknown"}
    assert ItoReason.objects.filter(pk="unassigned").exists()


def test_no_other_segment_type_can_be_added(admin_client):
    assert admin_client.get(reverse("admin:events_segmenttype_add")).status_code == 403


def test_editing_a_note_in_admin_goes_through_the_notes_service(admin_client, leg):
    from events.services import notes

    note = notes.add_note(segments.new_manual_segment(leg), text="first")
    url = reverse("admin:events_note_change", args=[note.pk])
    assert admin_client.post(url, {"text": "second"}).status_code == 302
    edited = type(note).objects.get(pk=note.pk)
    assert edited.text == "second" and edited.edited > note.edited
    segment_page = admin_client.get(reverse("admin:events_segment_change", args=[note.segment_id]))
    assert b'name="notes-0-text"' not in segment_page.content


class _FormFields(HTMLParser):
    """The values a browser would post for the admin change form of a page."""

    def __init__(self):
        super().__init__()
        self.data, self._select, self._textarea = {}, None, None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        name = a.get("name")
        if tag == "input" and name and a.get("type") not in ("submit", "checkbox", "file"):
            self.data[name] = a.get("value") or ""
        elif tag == "input" and name and a.get("type") == "checkbox" and "checked" in a:
            self.data[name] = a.get("value") or "on"
        elif tag == "select" and name:
            self._select = name
            self.data.setdefault(name, "")
        elif tag == "option" and self._select and "selected" in a:
            self.data[self._select] = a.get("value") or ""
        elif tag == "textarea" and name:
            self._textarea = name
            self.data[name] = ""

    def handle_endtag(self, tag):
        if tag == "select":
            self._select = None
        elif tag == "textarea":
            self._textarea = None

    def handle_data(self, data):
        if self._textarea:
            self.data[self._textarea] += (
                data.lstrip("\n") if not self.data[self._textarea] else data
            )


def _resave(client, url, **changes):
    parser = _FormFields()
    parser.feed(client.get(url).content.decode())
    parser.data.pop("csrfmiddlewaretoken", None)
    response = client.post(url, {**parser.data, **changes})
    assert response.status_code == 302, response.content.decode()[:3000]


def test_each_level_with_children_can_be_saved_from_its_admin_page(admin_client, leg):
    """The read-only inlines list non-editable columns (numbers); saving must not trip on them."""
    from events.services import notes

    master = segments.report_mode(leg, "ito").master
    child = master.children.get()
    notes.add_note(child, text="seen from the tower")
    shift, event = leg.shift, leg.shift.test_event
    _resave(admin_client, reverse("admin:events_testevent_change", args=[event.pk]), note="Ü")
    _resave(admin_client, reverse("admin:events_shift_change", args=[shift.pk]), workspace="pit")
    _resave(admin_client, reverse("admin:events_leg_change", args=[leg.pk]), note="wet")
    _resave(admin_client, reverse("admin:events_segment_change", args=[child.pk]), slope="5 %")
    _resave(admin_client, reverse("admin:events_segment_change", args=[master.pk]))
    event.refresh_from_db(), shift.refresh_from_db(), leg.refresh_from_db(), child.refresh_from_db()
    assert (event.note, shift.workspace, leg.note, child.slope) == ("Ü", "pit", "wet", "5 %")
    assert shift.legs.get() == leg and leg.segments.filter(parent=None).get() == master


def test_each_level_can_be_added_from_its_admin_page(admin_client, vehicle, pose_source):
    from events.models import Leg, Shift, TestEvent

    _resave(
        admin_client,
        reverse("admin:events_testevent_add"),
        location="Übungsplatz Süd",
        time_zone="Europe/Berlin",
    )
    event = TestEvent.objects.get()
    _resave(
        admin_client, reverse("admin:events_shift_add"), test_event=event.pk, vehicle=vehicle.pk
    )
    shift = Shift.objects.get()
    _resave(
        admin_client,
        reverse("admin:events_leg_add"),
        shift=shift.pk,
        default_pose_source=pose_source.pk,
    )
    leg = Leg.objects.get()
    assert (event.location, shift.number, leg.number) == ("Übungsplatz Süd", 1, 1)
    assert leg.is_open and leg.default_pose_source == pose_source


def test_admin_shows_and_edits_which_vehicles_a_robot_logs_for(
    admin_client, robot_client, vehicle, other_vehicle
):
    robot = robot_client(vehicle).user
    account = robot.robot_account
    vehicle_page = admin_client.get(reverse("admin:events_vehicle_change", args=[vehicle.pk]))
    assert vehicle_page.status_code == 200
    html = vehicle_page.content.decode()
    assert "robot accounts logging for this vehicle" in html.lower()
    assert f'<option value="{account.pk}" selected>{robot.username}</option>' in html

    user_page = admin_client.get(reverse("admin:auth_user_change", args=[robot.pk]))
    assert user_page.status_code == 200
    html = user_page.content.decode()
    assert "robot account (vehicles it logs for)" in html.lower()
    assert f'<option value="{vehicle.pk}" selected>' in html

    listing = admin_client.get(reverse("admin:events_robotaccount_changelist")).content.decode()
    assert robot.username in listing and vehicle.key in listing

    url = reverse("admin:events_robotaccount_change", args=[account.pk])
    saved = admin_client.post(url, {"user": robot.pk, "vehicles": [other_vehicle.pk]})
    assert saved.status_code == 302, saved.content
    assert list(account.vehicles.all()) == [other_vehicle]


def test_operators_see_but_do_not_change_robot_bindings(client, robot_client, vehicle):
    client.force_login(staff_user("operator"))
    account = robot_client(vehicle).user.robot_account
    url = reverse("admin:events_robotaccount_change", args=[account.pk])
    page = client.get(url)
    assert page.status_code == 200
    assert b'name="vehicles"' not in page.content
    client.post(url, {"user": account.user.pk, "vehicles": []})
    assert list(account.vehicles.all()) == [vehicle]
