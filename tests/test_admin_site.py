"""The admin is branded and separates configuration from recorded data."""

import pytest
from django.contrib.auth.models import Group, User

pytestmark = pytest.mark.django_db


def test_admin_is_branded_and_grouped_with_proper_names(client):
    client.force_login(User.objects.create_superuser("root", password="pw"))
    page = client.get("/admin/").content.decode()
    assert "FTT administration" in page and "Django administration" not in page
    configuration = page.index(">Configuration</a>")
    recorded = page.index(">Recorded data</a>")
    assert "ITO reasons" in page and "Ito reasons" not in page
    # Vehicles and reasons under Configuration, shifts and segments under Recorded data.
    assert configuration < page.index("Vehicles") < page.index("ITO reasons") < recorded
    assert recorded < page.index("Shifts") and recorded < page.index("Segments")


def test_vehicle_key_says_where_the_collector_uses_it(client):
    client.force_login(User.objects.create_superuser("root", password="pw"))
    page = client.get("/admin/events/vehicle/add/").content.decode()
    assert "ftt_collect --vehicle" in page


def test_a_robot_account_is_kept_out_of_admin_even_as_staff(client, robot_client, vehicle):
    robot = robot_client(vehicle).user
    robot.is_staff = True
    robot.save()
    client.force_login(robot)
    assert client.get("/admin/").status_code == 302
    assert client.get("/admin/telemetry/pose/").status_code == 302
    people = User.objects.create_user("op", password="pw", is_staff=True)
    people.groups.add(Group.objects.get(name="operator"))
    client.force_login(people)
    assert client.get("/admin/").status_code == 200


def test_an_operator_is_made_on_one_page_with_role_and_name(client):
    from events.models import Personnel

    client.force_login(User.objects.create_superuser("root", password="pw"))
    page = client.get("/admin/auth/user/add/").content.decode()
    # A person's login: no robot block on the add page, the role on it.
    assert "vehicles it logs for" not in page and 'name="role"' in page
    response = client.post(
        "/admin/auth/user/add/",
        {
            "username": "olga",
            "usable_password": "true",
            "password1": "a-Long-pass-123",
            "password2": "a-Long-pass-123",
            "role": "operator",
            "person_name": "Olga Operator",
            "institution": "FKIE",
        },
    )
    assert response.status_code == 302
    olga = User.objects.get(username="olga")
    assert list(olga.groups.values_list("name", flat=True)) == ["operator"]
    assert not olga.is_staff
    assert Personnel.objects.get(user=olga).name == "Olga Operator"


def test_library_sections_are_for_superusers_only(client):
    staff = User.objects.create_user("ada", password="pw", is_staff=True)
    staff.groups.add(Group.objects.get(name="administrator"))
    client.force_login(staff)
    page = client.get("/admin/").content.decode()
    assert "Vehicles" in page
    assert "Access attempts" not in page and "Tokens" not in page
    client.force_login(User.objects.create_superuser("root", password="pw"))
    page = client.get("/admin/").content.decode()
    assert "Access attempts" in page
    assert "default basemaps of test events" in page.lower()


def test_segments_are_listed_with_the_guis_numbers(client, vehicle):
    from events.models import Segment
    from events.services import logs, segments

    event = logs.create_test_event(location="Same field", version="1.0")
    twin = logs.create_test_event(location="Same field", version="1.0")
    leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
    segments.report_mode(leg, "auto")
    segments.report_mode(leg, "ito", reason="safety")
    client.force_login(User.objects.create_superuser("root", password="pw"))
    page = client.get("/admin/events/segment/").content.decode()
    assert "Leg 1 · #2.1 ITO reason" in page and "Leg 1 · #1 AUTO run" in page
    assert " child #" not in page and " master #" not in page
    child = Segment.objects.get(parent__isnull=False)
    assert (
        "Leg 1 · #2.1" in client.get(f"/admin/events/segment/{child.pk}/change/").content.decode()
    )
    # Two test events of one name and day differ in choice lists.
    assert str(event) != str(twin)
