"""The generic CRUD suite applied to every endpoint of the events app."""

import pytest

from common import roles
from events.models import ItoReason, Note, Personnel, SegmentType, Weather
from events.services import logs, notes, segments
from tests.support.api import CrudTests, assert_error_shape


class TestTestEvents(CrudTests):
    basename = "test-event"

    @pytest.fixture
    def instance(self, test_event):
        return test_event

    @pytest.fixture
    def create_data(self):
        return {"location": "Meppen", "version": "2", "time_zone": "Europe/Berlin"}

    @pytest.fixture
    def update_data(self):
        return {"location": "Hammelburg", "note": "moved"}


class TestShifts(CrudTests):
    basename = "shift"

    @pytest.fixture
    def instance(self, shift):
        return shift

    @pytest.fixture
    def create_data(self, test_event, other_vehicle, person):
        return {
            "test_event": test_event.pk,
            "vehicle": other_vehicle.pk,
            "test_director": person.pk,
            "test_intent": "endurance",
        }

    @pytest.fixture
    def update_data(self, person):
        return {"workspace": "north field", "safety_officer": person.pk}


class TestLegs(CrudTests):
    basename = "leg"

    @pytest.fixture
    def instance(self, leg):
        return leg

    @pytest.fixture
    def create_data(self, shift, pose_source):
        return {"shift": shift.pk, "weather": "rainy", "default_pose_source": pose_source.pk}

    @pytest.fixture
    def update_data(self):
        return {"weather": "foggy", "recording": "/bags/leg1.mcap"}


class TestSegments(CrudTests):
    basename = "segment"
    operations = ("update", "delete")

    @pytest.fixture
    def instance(self, leg):
        return segments.new_manual_segment(leg)

    @pytest.fixture
    def create_data(self):
        return {}

    @pytest.fixture
    def update_data(self):
        return {"ito_reason": "safety", "obstacle": "a fallen tree", "slope": "10°"}


class TestNotes(CrudTests):
    basename = "note"

    @pytest.fixture
    def instance(self, leg, person):
        segment = segments.new_manual_segment(leg)
        return notes.add_note(segment, text="Stopped at the gate", author=person)

    def writer(self, api_client, instance):
        client = api_client(roles.OPERATOR)
        instance.author.user = client.user
        instance.author.save()
        return client

    @pytest.fixture
    def create_data(self, instance):
        return {"segment": instance.segment_id, "text": "Battery swap"}

    @pytest.fixture
    def update_data(self):
        return {"text": "Stopped at the second gate"}

    def test_author_defaults_to_the_person_of_the_login(self, api_client, instance, person):
        client = api_client(roles.OPERATOR)
        person.user = client.user
        person.save()
        response = client.post(
            self.list_url(), {"segment": instance.segment_id, "text": "mine"}, format="json"
        )
        assert response.status_code == 201, response.content
        assert response.json()["author_name"] == person.name
        assert Note.objects.get(pk=response.json()["id"]).author == person

    def test_an_operator_cannot_write_in_someone_elses_name(self, api_client, instance, person):
        response = api_client(roles.OPERATOR).post(
            self.list_url(),
            {"segment": instance.segment_id, "text": "spoof", "author": person.pk},
            format="json",
        )
        assert_error_shape(response, 403)
        assert not Note.objects.filter(text="spoof").exists()

    def test_an_administrator_may_name_the_author(self, api_client, instance, person):
        response = api_client(roles.ADMINISTRATOR).post(
            self.list_url(),
            {"segment": instance.segment_id, "text": "for Ada", "author": person.pk},
            format="json",
        )
        assert response.status_code == 201 and response.json()["author"] == person.pk

    def test_only_the_author_and_administrators_change_a_note(self, api_client, instance):
        other = api_client(roles.OPERATOR)
        assert_error_shape(other.patch(self.detail_url(instance), {"text": "x"}), 403)
        assert_error_shape(other.delete(self.detail_url(instance)), 403)
        instance.refresh_from_db()
        assert instance.text == "Stopped at the gate"
        admin = api_client(roles.ADMINISTRATOR)
        assert admin.patch(self.detail_url(instance), {"text": "fixed"}).status_code == 200
        assert admin.delete(self.detail_url(instance)).status_code == 204


class ConfigurationCrud(CrudTests):
    write_role = roles.ADMINISTRATOR


class TestPersonnel(ConfigurationCrud):
    basename = "personnel"

    @pytest.fixture
    def instance(self, person):
        return person

    @pytest.fixture
    def create_data(self):
        return {"name": "Ada", "institution": "TU"}

    @pytest.fixture
    def update_data(self):
        return {"institution": "Uni Bonn"}

    def test_in_use_cannot_be_deleted_and_says_where(self, api_client, shift, person):
        response = api_client(roles.ADMINISTRATOR).delete(self.detail_url(person))
        assert response.status_code == 409
        assert "Shift 1" in response.json()["detail"]
        assert Personnel.objects.filter(pk=person.pk).exists()


class TestPerformers(ConfigurationCrud):
    basename = "performer"

    @pytest.fixture
    def instance(self, performer):
        return performer

    @pytest.fixture
    def create_data(self):
        return {"institution": "DLR"}

    @pytest.fixture
    def update_data(self):
        return {"institution": "DLR Oberpfaffenhofen"}


class TestVehicles(ConfigurationCrud):
    basename = "vehicle"

    @pytest.fixture
    def instance(self, vehicle):
        return vehicle

    @pytest.fixture
    def create_data(self):
        return {"key": "spot-2", "short_description": "Spot", "institution": "FKIE"}

    @pytest.fixture
    def update_data(self):
        return {"configuration": "lidar + camera"}

    def test_addressed_by_key(self, api_client, vehicle):
        response = api_client(roles.VIEWER).get(self.detail_url(vehicle.key))
        assert response.status_code == 200
        assert response.json()["id"] == vehicle.pk


class TestPoseSources(ConfigurationCrud):
    basename = "pose-source"

    @pytest.fixture
    def instance(self, pose_source):
        return pose_source

    @pytest.fixture
    def create_data(self):
        return {"key": "odom", "short_description": "Wheel odometry"}

    @pytest.fixture
    def update_data(self):
        return {"long_description": "Fused with the IMU"}


class TestWeather(ConfigurationCrud):
    basename = "weather"

    @pytest.fixture
    def instance(self, db):
        return Weather.objects.create(key="windy", short_description="windy")

    @pytest.fixture
    def create_data(self):
        return {"key": "hail", "short_description": "hail"}

    @pytest.fixture
    def update_data(self):
        return {"icon": "wind"}


class TestItoReasons(ConfigurationCrud):
    basename = "ito-reason"

    @pytest.fixture
    def instance(self, db):
        return ItoReason.objects.create(key="wildlife", short_description="Wildlife", color="0,0,0")

    @pytest.fixture
    def create_data(self):
        return {"key": "gps_loss", "short_description": "GPS lost", "color": "10,20,30"}

    @pytest.fixture
    def update_data(self):
        return {"counts_as_intervention": False}

    def test_the_reason_the_rules_use_cannot_be_deleted(self, api_client):
        response = api_client(roles.ADMINISTRATOR).delete(self.detail_url("unassigned"))
        assert response.status_code == 409
        assert ItoReason.objects.filter(pk="unassigned").exists()

    def test_key_cannot_be_renamed(self, api_client, instance):
        response = api_client(roles.ADMINISTRATOR).patch(
            self.detail_url(instance), {"key": "renamed"}, format="json"
        )
        assert response.status_code == 200
        assert ItoReason.objects.filter(pk="wildlife").exists()
        assert not ItoReason.objects.filter(pk="renamed").exists()


class TestSegmentTypes(ConfigurationCrud):
    basename = "segment-type"
    operations = ("update",)

    @pytest.fixture
    def instance(self, db):
        return SegmentType.objects.get(pk=SegmentType.AUTO)

    @pytest.fixture
    def create_data(self):
        return {}

    @pytest.fixture
    def update_data(self):
        return {"color": "0,128,255"}


def test_catalogues_are_readable_by_viewers_in_full(api_client, db):
    client = api_client(roles.VIEWER)
    assert len(client.get("/api/weather/").json()) == 6
    reasons = {r["key"]: r for r in client.get("/api/ito-reasons/").json()}
    assert len(reasons) == 12
    assert reasons["goal"]["counts_as_intervention"] is False
    types = {r["key"] for r in client.get("/api/segment-types/").json()}
    assert types == {"ito", "auto", "unknown"}


def test_token_endpoint_gives_a_working_token(client, role_user):
    user = role_user(roles.OPERATOR)
    response = client.post(
        "/api/token/",
        {"username": user.username, "password": "pw"},
        content_type="application/json",
    )
    assert response.status_code == 200
    token = response.json()["token"]
    assert client.get("/api/legs/", HTTP_AUTHORIZATION=f"Token {token}").status_code == 200
    bad = client.post(
        "/api/token/",
        {"username": user.username, "password": "no"},
        content_type="application/json",
    )
    assert bad.status_code == 400
    assert bad.json()["errors"]


def test_session_login_works_for_the_gui(client, role_user, leg):
    client.force_login(role_user(roles.VIEWER))
    assert client.get("/api/legs/").json()["results"][0]["id"] == leg.pk


def test_shift_for_a_closed_event_is_a_409_with_message(api_client, test_event, vehicle):
    logs.close_test_event(test_event)
    response = api_client(roles.OPERATOR).post(
        "/api/shifts/", {"test_event": test_event.pk, "vehicle": vehicle.pk}, format="json"
    )
    assert response.status_code == 409
    assert "closed" in response.json()["detail"]
