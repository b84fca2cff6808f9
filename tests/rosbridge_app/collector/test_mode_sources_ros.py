"""Mode from the robot's own topics over DDS: one drill with a MAVROS-like State
and an Autoware-like OperationModeState (built from the .msg files of
robot_msgs/, not installed packages), a String and an e-stop that vetoes; and
a source's switch placed at its header stamp when the collector hears it late."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from events.models import Segment
from tests.support.ros import ROOT, requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
SOURCES = """
rule: any_ito
sources:
  - {topic: /mavros/state, type: ftt_robot_msgs/msg/State, field: mode,
     auto: [OFFBOARD, AUTO.MISSION], ito: [MANUAL, POSCTL]}
  - {topic: /autoware/operation_mode, type: ftt_robot_msgs/msg/OperationModeState,
     field: mode, auto: [2], ito: [{min: 3, max: 4}, 1]}
  - {topic: /mode_text, type: std_msgs/msg/String, field: data,
     auto: [AUTO], ito: [MANUAL, TELEOP]}
  - {topic: /estop, type: std_msgs/msg/Bool, field: data, ito: [true]}
"""
STATE, OPERATION, TEXT, ESTOP = "/mavros/state", "/autoware/operation_mode", "/mode_text", "/estop"
ALIVE = "/localization/alive"
REASONS = f"""
window: 2.0
rules:
  - {{topic: {ESTOP}, type: std_msgs/msg/Bool, field: data, values: [true], reason: safety}}
  - {{topic: {ALIVE}, type: std_msgs/msg/Empty, silent: 1.0, reason: other}}
"""
AUTO_ALL = {
    STATE: {"mode": "OFFBOARD"},
    OPERATION: {"mode": 2},
    TEXT: {"data": "AUTO"},
    ESTOP: {"data": False},
}
# (seconds, changes, the combined mode the script means, the reason the robot
# suggests at a switch to ITO). Topics change one per phase where that
# matters: they are published one after the other; None: the topic falls silent.
PHASES = [
    (1.5, {STATE: {"mode": "MANUAL"}, OPERATION: {"mode": 1}, TEXT: {"data": "MANUAL"},
           ESTOP: {"data": False}, ALIVE: {}}, "ito", None),
    (1.5, AUTO_ALL, "auto", None),
    (1.5, {ESTOP: {"data": True}}, "ito", "safety"),
    (1.5, {STATE: {"mode": "POSCTL"}}, "ito", None),  # a switch during the e-stop
    (1.5, {STATE: {"mode": "OFFBOARD"}}, "ito", None),
    (1.5, {ESTOP: {"data": False}, ALIVE: None}, "auto", None),
    (1.5, {OPERATION: {"mode": 4}}, "ito", "other"),  # REMOTE, localisation silent
    (1.5, {TEXT: {"data": "TELEOP"}}, "ito", None),
    (1.5, {OPERATION: {"mode": 2}}, "ito", None),
    (1.5, {TEXT: {"data": "AUTO"}}, "auto", None),
]  # fmt: skip


def test_modes_from_the_robots_own_topics_and_an_estop(
    ros, procs, start_collector, robot_leg, robot_interfaces, tmp_path
):
    start_collector(
        params={"params.mode_sources": SOURCES, "params.reason_rules": REASONS},
        env=robot_interfaces,
    )
    assert ros.set_logging(True).success
    script = tmp_path / "script.json"
    topics = {
        STATE: "ftt_robot_msgs/msg/State",
        OPERATION: "ftt_robot_msgs/msg/OperationModeState",
        TEXT: "std_msgs/msg/String",
        ESTOP: "std_msgs/msg/Bool",
        ALIVE: "std_msgs/msg/Empty",
    }
    script.write_text(json.dumps({"topics": topics, "rate": 10, "phases": [p[:2] for p in PHASES]}))
    robot = subprocess.run(
        [sys.executable, "-m", "tests.support.scripted_robot", str(script)],
        cwd=ROOT,
        env={**procs.env, **robot_interfaces},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert robot.returncode == 0, robot.stderr

    def masters():
        return list(
            Segment.objects.filter(leg=robot_leg, parent__isnull=True)
            .order_by("start")
            .values_list("segment_type_id", flat=True)
        )

    switches = [p for i, p in enumerate(PHASES) if i == 0 or p[2] != PHASES[i - 1][2]]
    expected = [p[2] for p in switches]
    wait_for(lambda: len(masters()) >= len(expected), 20, what="the scripted switches")
    assert masters() == expected
    # Suggestions only: the reasons stay unassigned until the operator confirms.
    takeovers = Segment.objects.filter(leg=robot_leg, parent__isnull=False).order_by("start")
    assert [(t.suggested_reason_id, t.ito_reason_id) for t in takeovers] == [
        (p[3], "unassigned") for p in switches if p[2] == "ito"
    ]


# A robot whose State carries the time of the switch in its header: MANUAL at
# 5 Hz, then, told so on its input, OFFBOARD stamped when it switched and sent
# 0.3 s later (its DDS send time is not the switch); it prints that stamp.
STAMPED_ROBOT = """
import select, sys, time
import rclpy
from ftt_robot_msgs.msg import State
rclpy.init()
node = rclpy.create_node("stamped_robot")
pub = node.create_publisher(State, "/mavros/state", 100)
deadline = time.monotonic() + 30
while pub.get_subscription_count() == 0:
    if time.monotonic() > deadline:
        sys.exit("no subscriber")
    time.sleep(0.05)
print("ready", flush=True)
mode, stamp = "MANUAL", None
while True:
    if select.select([sys.stdin], [], [], 0.2)[0]:
        if not sys.stdin.readline():
            break
        mode, stamp = "OFFBOARD", time.time()
        print(repr(stamp), flush=True)
        time.sleep(0.3)
    msg = State(mode=mode)
    t = stamp if stamp is not None else time.time()
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round(t % 1 * 1e9))
    pub.publish(msg)
    stamp = None
"""


def test_a_mode_source_with_a_header_switches_at_its_stamp_when_the_collector_is_late(
    ros, procs, start_collector, robot_leg, robot_interfaces
):
    sources = (
        "sources: [{topic: /mavros/state, type: ftt_robot_msgs/msg/State, field: mode,"
        " auto: [OFFBOARD], ito: [MANUAL]}]"
    )
    collector = start_collector(params={"params.mode_sources": sources}, env=robot_interfaces)
    assert ros.set_logging(True).success
    robot = subprocess.Popen(
        [sys.executable, "-c", STAMPED_ROBOT],
        cwd=ROOT,
        env={**procs.env, **robot_interfaces},
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert robot.stdout.readline() == "ready\n"
        wait_for(
            lambda: Segment.objects.filter(leg=robot_leg, segment_type_id="ito").exists(),
            what="the ITO master",
        )
        # The robot's computer starves the collector: it hears nothing for 2 s.
        os.kill(collector.popen.pid, signal.SIGSTOP)
        try:
            robot.stdin.write("switch\n")
            robot.stdin.flush()
            stamp = float(robot.stdout.readline())
            time.sleep(2)  # the starvation itself, not a wait for something
        finally:
            os.kill(collector.popen.pid, signal.SIGCONT)
        resumed = time.time()
        master = wait_for(
            lambda: Segment.objects.filter(leg=robot_leg, segment_type_id="auto").first(),
            what="the AUTO master",
        )
    finally:
        robot.stdin.close()
        robot.wait(10)
    assert resumed - stamp > 2
    assert master.start.timestamp() == pytest.approx(stamp, abs=0.001)
    assert master.robot_stamp == master.start
    assert master.start_uncertainty == 0.0
