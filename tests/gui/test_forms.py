"""The dialogs' fields come from the server: labels, kinds, choices, help and
what a new entry starts with, so the page declares no field of its own."""

import pytest
from django.contrib.auth.models import Group, User

from events.models import Performer, Personnel, PoseSource, Vehicle

pytestmark = pytest.mark.django_db


def forms_of(client, person=None):
    user = User.objects.create_user("otto", password="pw")
    user.groups.add(Group.objects.get(name="operator"))
    if person is not None:
        person.user = user
        person.save()
    client.force_login(user)
    return client.get("/gui/api/forms/").json()


def field(form, name):
    return next(f for f in form["fields"] if f["name"] == name)


def test_every_log_field_is_described_with_its_label_and_kind(client, vehicle):
    forms = forms_of(client)

    assert [f["name"] for f in forms["event"]["fields"]] == [
        "location",
        "version",
        "time_zone",
        "language",
        "note",
    ]
    time_zone = field(forms["event"], "time_zone")
    assert time_zone["label"] == "Time zone"
    assert "Europe/Berlin" in time_zone["help"] and "Europe/Berlin" in time_zone["suggestions"]
    assert field(forms["event"], "note")["type"] == "textarea"
    assert field(forms["shift"], "vehicle") | {"choices": None} == {
        "name": "vehicle",
        "label": "Vehicle",
        "help": "",
        "required": True,
        "type": "select",
        "choices": None,
        "max_length": None,
    }
    assert field(forms["shift"], "vehicle")["choices"] == [[vehicle.pk, "Husky A200"]]
    assert field(forms["shift"], "performer")["required"] is False


def test_weather_choices_are_the_catalogues_words_and_nothing_is_preset(client):
    leg_form = forms_of(client)["leg"]

    weather = field(leg_form, "weather")
    assert ["sunny", "Sunny"] in weather["choices"]
    assert all(label[0].isupper() for _, label in weather["choices"])
    assert "weather" not in leg_form["initial"]


def test_a_new_shift_starts_with_the_user_and_the_only_vehicle(client, vehicle):
    Performer.objects.create(institution="Fraunhofer FKIE")
    own = Performer.objects.create(institution="FKIE")
    me = Personnel.objects.create(name="Jörg Müller", institution="FKIE")

    initial = forms_of(client, me)["shift"]["initial"]

    assert initial == {
        "vehicle": vehicle.pk,
        "performer": own.pk,
        "test_administrator": me.pk,
        "test_director": me.pk,
        "robot_operator": me.pk,
        "safety_officer": me.pk,
    }


def test_with_two_vehicles_or_pose_sources_none_is_chosen_for_the_user(client, vehicle):
    Vehicle.objects.create(key="jackal", short_description="Jackal")
    PoseSource.objects.create(key="gps", short_description="GPS")
    PoseSource.objects.create(key="odom", short_description="Odometry")

    forms = forms_of(client)

    assert forms["shift"]["initial"] == {}
    assert forms["leg"]["initial"] == {}


def test_without_a_vehicle_a_shift_cannot_be_started_and_the_dialog_says_why(client):
    forms = forms_of(client)

    assert "Configure a vehicle first" in forms["shift"]["unavailable"]
    assert forms["event"]["unavailable"] == ""


def test_the_report_dialog_offers_gps_or_local_with_gps_first_and_says_the_zoom_range(client):
    report = forms_of(client)["report"]

    # A compact report without the camera appendix unless asked for.
    assert report["initial"] == {
        "version": "1.0",
        "local": "false",
        "level": "standard",
        "image_appendix": "false",
    }
    assert [value for value, _ in field(report, "level")["choices"]] == [
        "summary",
        "standard",
        "full",
    ]
    assert field(report, "local")["choices"] == [["false", "GPS"], ["true", "Local (map frame)"]]
    assert field(report, "max_zoom")["type"] == "number"
    assert "1–19" in field(report, "max_zoom")["label"]
    assert field(report, "creator_address")["type"] == "textarea"


def test_the_leg_dialog_offers_the_chosen_test_events_cases_only(client, test_event):
    from django.contrib.gis.geos import MultiPolygon, Polygon

    from events.models import TestCase
    from events.services import logs

    other = logs.create_test_event(location="Elsewhere", time_zone="UTC")
    area = MultiPolygon(Polygon.from_bbox((7.0, 50.0, 7.1, 50.1)))
    mine = TestCase.objects.create(test_event=test_event, key="loop", title="Loop", area=area)
    TestCase.objects.create(test_event=other, key="hill", title="Hill")
    forms_of(client)

    chosen = client.get(f"/gui/api/forms/?event={test_event.pk}").json()
    assert field(chosen["leg"], "test_case")["choices"] == [[mine.pk, "Loop: Loop"]]
    # The place search offers the cases with an area, with the area as GeoJSON.
    (case,) = client.get("/gui/api/test-case-areas/").json()["cases"]
    assert case["id"] == mine.pk and case["test_event"] == test_event.pk
    assert case["area"]["type"] == "MultiPolygon"
