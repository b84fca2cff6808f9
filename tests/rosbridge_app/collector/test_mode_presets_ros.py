"""The mode-source presets over DDS (mode_presets.py, as docs/collector.md
prints them): a real rclpy robot publishes what an Autoware vehicle, a PX4
flight controller behind MAVROS and a robot with a mode string send, with
the values that tripped the presets up before (a mode still in transition, a
driver override, disarmed, ACRO, an unlisted string); the stored switches and
their times are the robot's. One collector for all three: each preset is set
as params.mode_sources in turn, as an operator would in the GUI editor.

The message types are built from robot_msgs/ftt_robot_msgs (the fields of
upstream's autoware_adapi_v1_msgs/OperationModeState and mavros_msgs/State,
test_mode_presets.py holds them together), so the presets' type names are
those of that package here."""

import json
import subprocess
import sys
from datetime import UTC, datetime

import pytest

from events.models import Segment
from rosbridge_app.collector.mode_presets import preset
from tests.support.ros import ROOT, requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
BUILT = {
    "autoware_adapi_v1_msgs/msg/OperationModeState": "ftt_robot_msgs/msg/OperationModeState",
    "mavros_msgs/msg/State": "ftt_robot_msgs/msg/State",
}
STOP, AUTONOMOUS, LOCAL = 1, 2, 3  # OperationModeState.mode


def operation(mode, transition=False, control=True):
    return {"mode": mode, "is_in_transition": transition, "is_autoware_control_enabled": control}


def state(armed, mode):
    return {"connected": True, "armed": armed, "mode": mode}


# Per preset: its topic, the robot's publishing (Autoware's state is a latched
# notification sent on change; MAVROS and the string are sent periodically)
# and its steps: (fields, the mode the robot is in).
PRESETS = {
    "autoware": (
        "/api/operation_mode/state",
        "on_change",
        [
            (operation(STOP), "ito"),
            (operation(AUTONOMOUS, transition=True), "ito"),  # the driver is still responsible
            (operation(AUTONOMOUS), "auto"),
            (operation(AUTONOMOUS, control=False), "ito"),  # the driver took the wheel
            (operation(AUTONOMOUS), "auto"),
            (operation(LOCAL), "ito"),  # the joystick
        ],
    ),
    "mavros": (
        "/mavros/state",
        "periodic",
        [
            (state(False, "AUTO.MISSION"), "ito"),  # on the ground, mission loaded
            (state(True, "AUTO.MISSION"), "auto"),
            (state(True, "ACRO"), "ito"),
            (state(True, "OFFBOARD"), "auto"),
            (state(False, "OFFBOARD"), "ito"),  # landed and disarmed
        ],
    ),
    "string": (
        "/robot/mode",
        "periodic",
        [
            ({"data": "AUTO"}, "auto"),
            ({"data": "manual"}, "ito"),  # values the preset does not list
            ({"data": "AUTO"}, "auto"),
            ({"data": "IDLE"}, "ito"),
        ],
    ),
}
TYPES = {
    "autoware": "ftt_robot_msgs/msg/OperationModeState",
    "mavros": "ftt_robot_msgs/msg/State",
    "string": "std_msgs/msg/String",
}

# Told a preset's name on its input, publishes its steps (0.6 s each; on change
# once, else at 5 Hz, each message stamped when sent) once the collector
# subscribes, and prints the time each step's first message was sent.
ROBOT = """
import importlib, json, sys, time
import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
plan = json.loads(sys.argv[1])
rclpy.init()
node = rclpy.create_node("preset_robot")
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
def cls(typename):
    pkg, kind, name = typename.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
publishers = {
    name: node.create_publisher(cls(p["type"]), p["topic"],
                                latched if p["publishing"] == "on_change" else 10)
    for name, p in plan.items()
}
print("ready", flush=True)
for line in sys.stdin:
    name = line.strip()
    p, pub, kind = plan[name], publishers[name], cls(plan[name]["type"])
    deadline = time.monotonic() + 30
    while pub.get_subscription_count() == 0:
        if time.monotonic() > deadline:
            sys.exit("no subscriber on " + p["topic"])
        time.sleep(0.05)
    firsts = []
    for fields in p["steps"]:
        end = time.monotonic() + 0.6
        first = None
        while time.monotonic() < end:
            msg = kind(**fields)
            t = time.time()
            stamp = msg.header.stamp if hasattr(msg, "header") else getattr(msg, "stamp", None)
            if stamp is not None:
                stamp.sec, stamp.nanosec = int(t), int(round(t % 1 * 1e9))
            pub.publish(msg)
            first = t if first is None else first
            if p["publishing"] == "on_change":
                break
            time.sleep(0.2)
        firsts.append(first)
        time.sleep(max(0.0, end - time.monotonic()))
    print(json.dumps(firsts), flush=True)
"""


def document(name: str) -> str:
    text = preset(name).document
    for upstream, built in BUILT.items():
        text = text.replace(upstream, built)
    return text


def masters(leg) -> list[tuple[str, float]]:
    return [
        (kind, start.timestamp())
        for kind, start in Segment.objects.filter(leg=leg, parent__isnull=True)
        .order_by("start")
        .values_list("segment_type_id", "start")
    ]


def test_each_preset_stores_the_switches_a_robot_of_its_kind_makes_at_their_times(
    ros, procs, start_collector, robot_leg, robot_interfaces
):
    from rclpy.parameter import Parameter

    order = ["autoware", "mavros", "string"]
    start_collector(
        params={"params.mode_sources": document(order[0]), "snapshot.enabled": False},
        env=robot_interfaces,
    )
    assert ros.set_logging(True).success
    params = ros.parameters()
    assert params.wait_for_services(10)
    plan = {
        name: {"topic": topic, "type": TYPES[name], "publishing": publishing, "steps": [
            fields for fields, _ in steps
        ]}
        for name, (topic, publishing, steps) in PRESETS.items()
    }  # fmt: skip
    robot = subprocess.Popen(
        [sys.executable, "-c", ROBOT, json.dumps(plan)],
        cwd=ROOT,
        env={**procs.env, **robot_interfaces},
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    expected: list[tuple[str, float, str]] = []
    try:
        assert robot.stdout.readline() == "ready\n"
        for name in order:
            if name != order[0]:
                set_to = params.set_parameters(
                    [Parameter("params.mode_sources", value=document(name))]
                )
                assert ros.await_future(set_to).results[0].successful
            robot.stdin.write(name + "\n")
            robot.stdin.flush()
            firsts = json.loads(robot.stdout.readline())
            for (_, mode), sent in zip(PRESETS[name][2], firsts, strict=True):
                if not expected or expected[-1][0] != mode:
                    expected.append((mode, sent, name))
            wait_for(
                lambda: len(masters(robot_leg)) >= len(expected),
                10,
                what=f"the switches of the {name} robot",
            )
    finally:
        robot.stdin.close()
        robot.wait(10)
    stored = masters(robot_leg)
    assert [kind for kind, _ in stored] == [kind for kind, _, _ in expected]
    for (kind, start), (_, sent, name) in zip(stored, expected, strict=True):
        # Autoware and MAVROS: the robot's stamp, exactly; the string: its DDS
        # send time, taken in publish() just after the robot read its clock.
        margin = 0.05 if name == "string" else 0.001
        assert start == pytest.approx(sent, abs=margin), (
            name,
            kind,
            datetime.fromtimestamp(sent, UTC),
        )
