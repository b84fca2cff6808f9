"""Black-box snapshots over real ROS 2: publishers → ftt_collect → MCAP files on the segment."""

import os
import re
import signal
import time
from datetime import timedelta

import pytest

from events.models import Segment
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.services.collectors import issue_command
from telemetry.models import Recording
from tests.support.mcap_files import read_mcap
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
BEFORE, AFTER = 3.0, 2.0
# No message is published this close to a window's edge, so which side of it a
# message falls on does not depend on the delivery delay.
MARGIN = 0.15


def latched():
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )


def wait_for_subscribers(publisher, count):
    wait_for(
        lambda: publisher.get_subscription_count() >= count,
        15,
        what=f"{count} subscriptions on {publisher.topic_name}",
    )


def take_over_snapshot(leg):
    """The ITO master of the leg and the snapshot attached to it, once stored."""
    ito = wait_for(
        lambda: Segment.objects.filter(leg=leg, parent=None, segment_type_id="ito").first(),
        10,
        what="the ITO master",
    )
    recording = wait_for(
        lambda: Recording.objects.filter(segment=ito).first(), 20, what="the take-over snapshot"
    )
    return ito, recording


def test_a_take_over_and_requests_give_snapshots_with_the_robots_messages(
    ros, start_collector, robot_leg
):
    from geometry_msgs.msg import TransformStamped
    from industrial_msgs.msg import RobotStatus
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool
    from tf2_msgs.msg import TFMessage

    mode = ros.publisher(Bool, "/robot_mode")
    fix = ros.publisher(NavSatFix, "/gps_fix", 100)
    status = ros.publisher(RobotStatus, "/robot_status", 100)
    tf_static = ros.publisher(TFMessage, "/tf_static", latched())
    static = TransformStamped(child_frame_id="gps")
    static.header.frame_id = "base_link"
    static.transform.translation.x = 0.42
    tf_static.publish(TFMessage(transforms=[static]))
    start_collector(
        params={
            "snapshot.before": BEFORE,
            "snapshot.after": AFTER,
            "snapshot.topics": "robot_mode, gps_fix, /tf_static, robot_status",
        }
    )
    # The collector's own subscriptions plus the raw ones of the black box.
    wait_for_subscribers(mode, 2)
    wait_for_subscribers(fix, 2)
    wait_for_subscribers(status, 1)
    assert ros.set_logging(True).success

    sent = {"/gps_fix": [], "/robot_status": []}
    base = time.time() + 0.5
    switch_at = base + 4.0
    edges = (switch_at - BEFORE, switch_at + AFTER)
    mode_sent = False
    for i in range(160):  # 8 s at 20 Hz
        at = base + i * 0.05
        time.sleep(max(0.0, at - time.time()))
        if not mode_sent and at >= switch_at:
            mode.publish(Bool(data=False))  # the take-over
            mode_sent = True
        if i == 10:
            mode.publish(Bool(data=True))  # auto, before the window
        if any(abs(at - edge) < MARGIN for edge in edges) or abs(at - switch_at) < MARGIN:
            continue
        fix.publish(NavSatFix(latitude=40.0 + i * 1e-4, longitude=9.0))
        sent["/gps_fix"].append((at, 40.0 + i * 1e-4))
        if i % 2 == 0:
            message = RobotStatus(error_code=i)
            message.mode.val = 1
            message.in_motion.val = 1
            status.publish(message)
            sent["/robot_status"].append((at, i))

    ito, recording = take_over_snapshot(robot_leg)
    # The window: from BEFORE seconds before the switch to AFTER seconds after it.
    assert abs(recording.start - (ito.start - timedelta(seconds=BEFORE))) < timedelta(
        milliseconds=1
    )
    assert abs(recording.end - (ito.start + timedelta(seconds=AFTER))) < timedelta(milliseconds=1)
    assert abs(ito.start.timestamp() - switch_at) < MARGIN / 2

    back = read_mcap(recording.file.path)
    assert back["profile"] == "ros2"
    by_topic: dict[str, list] = {}
    for topic, log_time, message in back["messages"]:
        by_topic.setdefault(topic, []).append((log_time, message))
    window = (recording.start.timestamp() * 1e9, recording.end.timestamp() * 1e9)
    for topic, messages in by_topic.items():
        assert all(window[0] <= t <= window[1] for t, _ in messages), topic

    def in_window(values):
        return [v for at, v in values if edges[0] < at < edges[1]]

    latitudes = [m.latitude for _, m in by_topic["/gps_fix"]]
    assert latitudes == pytest.approx(in_window(sent["/gps_fix"]))
    statuses = by_topic["/robot_status"]
    assert [m.error_code for _, m in statuses] == in_window(sent["/robot_status"])
    assert all(m.mode.val == 1 and m.in_motion.val == 1 for _, m in statuses)
    assert [m.data for _, m in by_topic["/robot_mode"]] == [False]
    # The static transform was published once, long before: repeated at the start.
    (static_back,) = by_topic["/tf_static"]
    assert static_back[1].transforms[0].transform.translation.x == pytest.approx(0.42)
    assert "MSG: industrial_msgs/TriState" in back["schemas"]["industrial_msgs/msg/RobotStatus"]
    assert recording.topics["/gps_fix"] == {
        "type": "sensor_msgs/msg/NavSatFix",
        "count": len(latitudes),
    }
    assert recording.message_count == len(back["messages"])
    assert recording.size == recording.file.size
    assert recording.reason == "switch to ITO"

    # On request: the ROS service, then the GUI's command.
    answer = ros.trigger("/ftt_snapshot")
    assert answer.success, answer.message
    command = issue_command(Collector.objects.get(name="collector"), CollectorCommand.Kind.SNAPSHOT)
    command = wait_for(
        lambda: CollectorCommand.objects.filter(pk=command.pk, done__isnull=False).first(),
        5,
        what="the snapshot command",
    )
    assert command.success, command.message
    requested = wait_for(
        lambda: (
            list(Recording.objects.filter(reason="on request"))
            if Recording.objects.filter(reason="on request").count() == 2
            else None
        ),
        15,
        what="the two requested snapshots",
    )
    assert {r.segment_id for r in requested} == {ito.pk}  # the open master
    for r in requested:
        assert r.end - r.start == timedelta(seconds=BEFORE + AFTER)
        assert read_mcap(r.file.path)["messages"]  # the tail of the drive


def test_a_killed_snapshot_writer_is_replaced_and_the_collector_goes_on(
    ros, start_collector, robot_leg
):
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool

    mode = ros.publisher(Bool, "/robot_mode")
    fix = ros.publisher(NavSatFix, "/gps_fix", 100)
    collector = start_collector(
        params={
            "snapshot.before": 5.0,
            "snapshot.after": 2.0,
            "snapshot.topics": "robot_mode, gps_fix",
        }
    )
    wait_for_subscribers(mode, 2)
    wait_for_subscribers(fix, 2)
    assert ros.set_logging(True).success
    mode.publish(Bool(data=True))
    latitudes = [40.0 + i * 1e-4 for i in range(20)]
    for latitude in latitudes:  # one second before the take-over, in its window
        fix.publish(NavSatFix(latitude=latitude, longitude=9.0))
        time.sleep(0.05)
    mode.publish(Bool(data=False))  # the take-over starts the snapshot writer
    started = wait_for(
        lambda: re.search(r"snapshot writer process started \(pid (\d+)\)", collector.output()),
        20,
        what="the snapshot writer",
    )
    writer = int(started.group(1))
    os.kill(writer, signal.SIGKILL)  # before or while it writes the take-over's window

    ito, recording = take_over_snapshot(robot_leg)
    assert f"snapshot writer process (pid {writer}) died" in collector.output()
    back = read_mcap(recording.file.path)  # written whole by the writer's successor
    assert len(back["messages"]) == recording.message_count
    assert [m.latitude for t, _, m in back["messages"] if t == "/gps_fix"] == pytest.approx(
        latitudes
    )
    mode.publish(Bool(data=True))  # and the collector still records
    wait_for(
        lambda: (
            Segment.objects.filter(leg=robot_leg, parent=None, start__gt=ito.start)
            .filter(segment_type_id="auto")
            .exists()
        ),
        10,
        what="the next AUTO master",
    )
    assert collector.alive()


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_stop_prints_no_traceback_from_the_snapshot_writer(ros, start_collector, stop):
    """A snapshot dropped for its size leaves the word of the writer started
    for it unread: the collector's exit then resets the pipe, not closes it."""
    from std_msgs.msg import String

    blob = ros.publisher(String, "/blob")
    collector = start_collector(
        params={
            "snapshot.before": 1.0,
            "snapshot.after": 4.0,
            "snapshot.topics": "blob",
            "snapshot.disk_budget_mb": 1,
        }
    )
    wait_for_subscribers(blob, 1)
    answer = ros.trigger("/ftt_snapshot")
    assert answer.success, answer.message
    for _ in range(40):  # 2.5 MB in the window, above the budget; paced, as a sensor's
        blob.publish(String(data="x" * 64 * 1024))
        time.sleep(0.02)
    wait_for(
        lambda: "MB is more than the disk budget" in collector.output(),
        20,
        what="the snapshot dropped for the disk budget",
    )
    assert "snapshot writer process started" in collector.output()
    assert collector.stop(stop) == 0
    output = collector.output()
    assert "Traceback" not in output, output
    assert "ConnectionResetError" not in output, output


def test_a_take_over_snapshot_holds_the_mode_source_and_reason_rule_topics(
    ros, start_collector, robot_leg
):
    """Default snapshot topics: a robot whose mode comes from a mode source
    (here the String preset) and whose take-over reasons come from a reason
    rule has both topics in its take-over's snapshot."""
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool, String

    from rosbridge_app.collector.mode_presets import preset

    mode = ros.publisher(String, "/robot/mode")
    estop = ros.publisher(Bool, "/safety/estop")
    fix = ros.publisher(NavSatFix, "/gps_fix", 100)
    start_collector(
        params={
            "params.mode_sources": preset("string").document,
            "params.reason_rules": (
                "rules: [{topic: /safety/estop, type: std_msgs/msg/Bool, field: data,"
                " values: [true], reason: safety}]"
            ),
            "snapshot.before": 3.0,
            "snapshot.after": 1.0,
        }
    )
    # Each: its input and the black box.
    wait_for_subscribers(mode, 2)
    wait_for_subscribers(estop, 2)
    assert ros.set_logging(True).success
    mode.publish(String(data="AUTO"))
    for i in range(10):
        fix.publish(NavSatFix(latitude=40.0 + i * 1e-4, longitude=9.0))
        if i % 5 == 0:
            estop.publish(Bool(data=False))
        time.sleep(0.1)  # the robot drives a second in AUTO
    estop.publish(Bool(data=True))  # the safety controller stops it ...
    mode.publish(String(data="manual"))  # ... and the operator takes over

    _, recording = take_over_snapshot(robot_leg)
    back = read_mcap(recording.file.path)
    modes = [m.data for topic, _, m in back["messages"] if topic == "/robot/mode"]
    assert modes == ["AUTO", "manual"]
    assert recording.topics["/robot/mode"] == {"type": "std_msgs/msg/String", "count": 2}
    # The e-stop may arrive just after the switch: the snapshot's "after" holds it.
    estops = [m.data for topic, _, m in back["messages"] if topic == "/safety/estop"]
    assert estops == [False, False, True]
    assert recording.topics["/safety/estop"] == {"type": "std_msgs/msg/Bool", "count": 3}
