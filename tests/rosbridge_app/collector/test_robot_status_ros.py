"""A team's own robot status over DDS (ftt_robot_msgs/RobotStatus, built from
the .msg files of robot_msgs/): a `level` enum and a nested
`safety.estop_pressed`, published by a real rclpy publisher the way drivers do
(BEST_EFFORT), read by mode sources as docs/collector.md describes them."""

import json
import subprocess
import sys

import pytest

from events.models import Segment
from rosbridge_app.models import Collector
from tests.support.ros import ROOT, requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
STATUS = "/robot/status"
STATUS_TYPE = "ftt_robot_msgs/msg/RobotStatus"
MANUAL, AUTO = 0, 1  # RobotStatus.LEVEL_*


def status(level: int, estop: bool = False) -> dict:
    return {"header": {}, "level": level, "safety": {"estop_pressed": estop}}


def run_robot(procs, robot_interfaces, tmp_path, phases, **script) -> None:
    path = tmp_path / "script.json"
    path.write_text(
        json.dumps({"topics": {STATUS: STATUS_TYPE}, "rate": 10, "phases": phases, **script})
    )
    robot = subprocess.run(
        [sys.executable, "-m", "tests.support.scripted_robot", str(path)],
        cwd=ROOT,
        env={**procs.env, **robot_interfaces},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert robot.returncode == 0, robot.stderr


def masters(leg) -> list[str]:
    return list(
        Segment.objects.filter(leg=leg, parent__isnull=True)
        .order_by("start")
        .values_list("segment_type_id", flat=True)
    )


def test_a_best_effort_status_topic_is_heard_and_the_gui_says_so(
    ros, procs, start_collector, robot_leg, robot_interfaces, tmp_path
):
    sources = (
        f"sources: [{{topic: {STATUS}, type: {STATUS_TYPE}, field: level,"
        f" auto: [{AUTO}], ito: [{MANUAL}]}}]"
    )
    start_collector(params={"params.mode_sources": sources}, env=robot_interfaces)
    assert ros.set_logging(True).success
    phases = [[1.5, {STATUS: status(MANUAL)}], [1.5, {STATUS: status(AUTO)}]]
    phases.append([1.5, {STATUS: status(MANUAL)}])
    run_robot(procs, robot_interfaces, tmp_path, phases, best_effort=[STATUS])
    wait_for(lambda: len(masters(robot_leg)) >= 3, 20, what="the three switches")
    assert masters(robot_leg) == ["ito", "auto", "ito"]
    inputs = Collector.objects.get(name="collector").inputs
    assert "best effort" in inputs["mode_source_0"]["qos"]


# The level and the e-stop inside the same message: the e-stop vetoes AUTO,
# and the reason rule on the same field suggests the take-over's reason.
ESTOP_SOURCES = f"""
rule: any_ito
sources:
  - {{topic: {STATUS}, type: {STATUS_TYPE}, field: level, auto: [{AUTO}], ito: [{MANUAL}]}}
  - {{topic: {STATUS}, type: {STATUS_TYPE}, field: safety.estop_pressed, ito: [true]}}
"""
ESTOP_REASONS = f"""
rules:
  - {{topic: {STATUS}, type: {STATUS_TYPE}, field: safety.estop_pressed, values: [true],
     reason: safety}}
"""


def test_an_estop_field_of_the_status_message_vetoes_auto(
    ros, procs, start_collector, robot_leg, robot_interfaces, tmp_path
):
    start_collector(
        params={"params.mode_sources": ESTOP_SOURCES, "params.reason_rules": ESTOP_REASONS},
        env=robot_interfaces,
    )
    assert ros.set_logging(True).success
    phases = [
        [1.5, {STATUS: status(MANUAL)}],
        [1.5, {STATUS: status(AUTO)}],
        [1.5, {STATUS: status(AUTO, estop=True)}],
        [1.5, {STATUS: status(AUTO)}],
    ]
    run_robot(procs, robot_interfaces, tmp_path, phases, best_effort=[STATUS])
    wait_for(lambda: len(masters(robot_leg)) >= 4, 20, what="the four switches")
    assert masters(robot_leg) == ["ito", "auto", "ito", "auto"]
    takeovers = Segment.objects.filter(leg=robot_leg, parent__isnull=False).order_by("start")
    assert [t.suggested_reason_id for t in takeovers] == [None, "safety"]


def test_a_value_mapping_the_field_can_never_hold_is_refused_and_the_switches_still_stored(
    ros, procs, start_collector, robot_leg, robot_interfaces, tmp_path
):
    from rclpy.parameter import Parameter

    good = (
        f"sources: [{{topic: {STATUS}, type: {STATUS_TYPE}, field: level,"
        f" auto: [{AUTO}], ito: [{MANUAL}]}}]"
    )
    start_collector(params={"params.mode_sources": good}, env=robot_interfaces)
    params = ros.parameters()
    assert params.wait_for_services(10)
    wrong = {
        # strings for the uint8 level
        f"sources: [{{topic: {STATUS}, type: {STATUS_TYPE}, field: level,"
        " auto: [AUTO], ito: [MANUAL]}]": "value 'AUTO' can never match level (uint8)",
        # ON/OFF unquoted: YAML's booleans, never a string's value
        "sources: [{topic: /mode_text, type: std_msgs/msg/String, field: data,"
        " auto: [ON], ito: [OFF]}]": "put the text in quotes",
    }
    for text, said in wrong.items():
        refused = ros.await_future(
            params.set_parameters([Parameter("params.mode_sources", value=text)])
        )
        assert not refused.results[0].successful
        assert said in refused.results[0].reason
    assert ros.set_logging(True).success
    phases = [[1.5, {STATUS: status(MANUAL)}], [1.5, {STATUS: status(AUTO)}]]
    run_robot(procs, robot_interfaces, tmp_path, phases)
    wait_for(lambda: len(masters(robot_leg)) >= 2, 20, what="the two switches")
    assert masters(robot_leg) == ["ito", "auto"]


def test_mode_sources_written_nested_in_the_parameters_file_are_read_and_saved_editable(
    ros, procs, start_collector, robot_leg, robot_interfaces, tmp_path
):
    import yaml

    from tests.support.ros import copy_default_params

    path = copy_default_params(tmp_path, vehicle="ros-bot").rename(tmp_path / "collector.yaml")
    data = yaml.safe_load(path.read_text())
    # The presets' shape, as docs/collector.md shows them, written into the file.
    data["ftt_collector"]["ros__parameters"]["params"]["mode_sources"] = {
        "rule": "any_ito",
        "sources": [
            {"topic": STATUS, "type": STATUS_TYPE, "field": "level", "auto": [AUTO]},
            {"topic": STATUS, "type": STATUS_TYPE, "field": "safety.estop_pressed", "ito": [True]},
        ],
    }
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    start_collector(env=robot_interfaces)
    assert ros.set_logging(True).success
    phases = [[1.5, {STATUS: status(AUTO)}], [1.5, {STATUS: status(AUTO, estop=True)}]]
    run_robot(procs, robot_interfaces, tmp_path, phases)
    wait_for(lambda: len(masters(robot_leg)) >= 2, 20, what="the two switches")
    assert masters(robot_leg) == ["auto", "ito"]
    saved = ros.trigger("/save_ftt_params")
    assert saved.success, saved.message
    text = path.read_text()
    # A literal block of the document's own lines, not one escaped string.
    assert "mode_sources: |" in text
    assert "field: safety.estop_pressed" in text
