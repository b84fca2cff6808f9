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
