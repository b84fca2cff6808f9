"""One parameter schema: the collector, the web side and the editor read it.

A wrong value is refused when the operator sends it, with a message under the
parameter's name, not later by the robot.
"""

import pytest
from django.db import connection
from django.utils import timezone

from rosbridge_app.collector.params import SPECS
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.selectors import control

pytestmark = pytest.mark.django_db


@pytest.fixture
def collector(vehicle):
    return Collector.objects.create(
        name="robot/husky",
        vehicle=vehicle,
        last_seen=timezone.now(),
        parameters={name: spec.default for name, spec in SPECS.items()},
        topics=[
            {"name": "/fix", "types": ["sensor_msgs/msg/NavSatFix"]},
            {"name": "/cam", "types": ["sensor_msgs/msg/Image"]},
        ],
    )


def send(client, collector, parameters):
    return client.post(
        f"/gui/api/collectors/{collector.pk}/commands/",
        {"kind": "set_parameters", "arguments": {"parameters": parameters}},
        content_type="application/json",
    )


@pytest.fixture
def operator(client, role_user):
    client.force_login(role_user("operator"))
    return client


@pytest.mark.parametrize(
    "name, value, message",
    [
        ("params.pose_min_distance", -1, "must be >= 0"),
        ("params.image_buffer_size", 500, "must be <= 20"),
        ("params.pose_min_period", "soon", "must be a number"),
        ("params.robot_mode_type", "joystick", "must be one of bool, industrial"),
        ("params.use_tf", 1, "must be true or false"),
        ("no.such.parameter", 1, "no such parameter"),
    ],
)
def test_a_wrong_value_is_refused_at_once_under_its_name(operator, collector, name, value, message):
    response = send(operator, collector, {name: value})
    assert response.status_code == 400, response.content
    assert message in " ".join(response.json()["errors"][name])
    assert not CollectorCommand.objects.exists()


def test_a_whole_number_is_taken_where_a_number_is_expected(operator, collector):
    response = send(operator, collector, {"params.pose_min_distance": 2})
    assert response.status_code == 202, response.content
    command = CollectorCommand.objects.get()
    assert command.arguments["parameters"] == {"params.pose_min_distance": 2.0}
    assert isinstance(command.arguments["parameters"]["params.pose_min_distance"], float)


def test_the_editor_rows_come_from_the_schema(operator, collector):
    rows = {
        r["name"]: r
        for r in operator.get(f"/gui/api/collectors/?vehicle={collector.vehicle_id}").json()[
            "parameters"
        ]
    }
    assert rows["params.image_buffer_size"]["minimum"] == 0
    assert rows["params.image_buffer_size"]["maximum"] == 20
    assert rows["params.image_buffer_size"]["type"] == "int"
    assert rows["params.robot_mode_type"]["choices"] == ["bool", "industrial"]
    assert rows["topics.gps_fix"]["expects"] == ["sensor_msgs/msg/NavSatFix"]
    assert rows["topics.gps_fix"]["suggestions"] == ["/fix"]
    assert rows["topics.robot_mode"]["expects"] == ["std_msgs/msg/Bool"]
    assert (
        rows["params.pose_min_distance"]["description"]
        == SPECS["params.pose_min_distance"].description
    )


@pytest.mark.parametrize("name", ["params.mode_sources", "params.reason_rules"])
def test_yaml_nested_too_deeply_is_refused_under_its_name(operator, collector, name):
    response = send(operator, collector, {name: "[" * 5000 + "]" * 5000})
    assert response.status_code == 400, response.content
    assert "nested too deeply" in " ".join(response.json()["errors"][name])
    assert not CollectorCommand.objects.exists()


SOURCE = "{topic: /mode, type: std_msgs/msg/String, field: data, auto: [A]}"


@pytest.mark.parametrize(
    "name, text, message",
    [
        # YAML aliases repeat one source or one list of values for two characters each.
        (
            "params.mode_sources",
            f"s: &s {SOURCE}\nsources: [{', '.join(['*s'] * 3000)}]",
            "sources has more than 100 entries",
        ),
        (
            "params.mode_sources",
            "v: &v " + "[" + ", ".join(["A"] * 101) + "]\n"
            "sources: [{topic: /mode, type: std_msgs/msg/String, field: data, auto: *v}]",
            "auto has more than 100 values",
        ),
        (
            "params.reason_rules",
            "r: &r {topic: /e, type: std_msgs/msg/String, field: data, values: [x], reason: X}\n"
            f"rules: [{', '.join(['*r'] * 3000)}]",
            "rules has more than 100 entries",
        ),
    ],
)
def test_a_document_of_thousands_of_entries_is_refused_under_its_name(
    operator, collector, name, text, message
):
    assert len(text) < 20_000
    response = send(operator, collector, {name: text})
    assert response.status_code == 400, response.content
    assert message in " ".join(response.json()["errors"][name])
    assert not CollectorCommand.objects.exists()


def test_a_parameter_is_checked_before_the_command_s_transaction(operator, collector, monkeypatch):
    # The embedded database takes its write lock when a transaction begins.
    depth_outside = len(connection.savepoint_ids)
    depths = []

    def check(name, value):
        depths.append(len(connection.savepoint_ids))
        return value

    monkeypatch.setattr(control, "check", check)
    response = send(operator, collector, {"params.mode_sources": f"sources: [{SOURCE}]"})
    assert response.status_code == 202, response.content
    assert depths == [depth_outside]
