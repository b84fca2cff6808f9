"""``manage.py ftt_robot_account`` makes a robot's login, binds it and prints its token."""

import io

import pytest
from django.contrib.auth.models import User
from django.core.management import CommandError, call_command
from rest_framework.test import APIClient

from common import roles
from common.models import DirectoryAccount
from events.models import RobotAccount


def _run(*args) -> str:
    out, err = io.StringIO(), io.StringIO()
    call_command("ftt_robot_account", *args, stdout=out, stderr=err)
    assert "robot account" in err.getvalue()
    return out.getvalue().strip()


def test_it_prints_a_token_that_logs_for_the_vehicle_only(vehicle, other_vehicle, leg):
    token = _run("husky-robot", "--vehicle", vehicle.key)
    account = RobotAccount.objects.get(user__username="husky-robot")
    assert list(account.vehicles.all()) == [vehicle]
    assert roles.is_robot(account.user)
    assert not account.user.has_usable_password()
    client = APIClient()
    client.credentials(HTTP_AUTHORIZATION=f"Token {token}")
    assert client.post(f"/api/legs/{leg.pk}/mode/", {"mode": "auto"}, format="json").status_code
    assert client.get(f"/api/vehicles/{vehicle.key}/current-leg/").status_code == 200
    assert client.get(f"/api/vehicles/{other_vehicle.key}/current-leg/").status_code == 403


def test_running_again_keeps_the_token_and_adds_vehicles(vehicle, other_vehicle):
    token = _run("husky-robot", "--vehicle", vehicle.key)
    assert _run("husky-robot", "--vehicle", other_vehicle.key) == token
    account = RobotAccount.objects.get(user__username="husky-robot")
    assert set(account.vehicles.all()) == {vehicle, other_vehicle}
    renewed = _run("husky-robot", "--vehicle", vehicle.key, "--new-token")
    assert renewed != token and len(renewed) == len(token)


def test_an_unknown_vehicle_is_refused_with_the_known_keys(vehicle):
    with pytest.raises(CommandError, match="No vehicle with key jackal.*husky"):
        _run("r", "--vehicle", "jackal")
    assert not User.objects.filter(username="r").exists()


def test_a_persons_account_is_not_turned_into_a_robot(role_user, vehicle):
    person = role_user(roles.OPERATOR)
    with pytest.raises(CommandError, match="person's account"):
        _run(person.username, "--vehicle", vehicle.key)
    assert not RobotAccount.objects.exists()
    assert not roles.is_robot(User.objects.get(pk=person.pk))


def test_a_directory_persons_account_is_not_turned_into_a_robot(vehicle):
    # Made by a directory sign-in, its person since removed from every role group.
    person = User.objects.create_user("dana")
    person.set_unusable_password()
    person.save()
    DirectoryAccount.objects.create(user=person)
    with pytest.raises(CommandError, match="person's account"):
        _run("dana", "--vehicle", vehicle.key)
    assert not RobotAccount.objects.exists()
