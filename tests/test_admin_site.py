"""The admin is branded and separates configuration from recorded data."""

import pytest
from django.contrib.auth.models import User

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
