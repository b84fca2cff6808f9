"""A robot that says its mode only on change, without a latched topic, over DDS:
what it drove before its first switch is stored under unknown mode, not under
the mode after the switch, the switch keeps its own time, and the statistics
say how much had no known mode (collector/unknown_mode.py); a collector
stopped while it waits for the first mode stores what it held."""

import math
import signal
import time

import pytest

from events.models import Segment
from reports.selectors.statistics import event_statistics
from rosbridge_app.models import Collector
from telemetry.models import LocalPose, Pose
from tests.support.fkie import gps_path_length
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
RATE = 10  # Hz of GPS and local pose
BEFORE_SWITCH = 4.0  # seconds driven before the robot's first mode message


# Every message kept and delivered, so the stored track is the one sent.
UNTHINNED = {
    "params.use_tf": False,
    "params.pose_min_distance": 0.0,
    "params.pose_min_period": 0.0,
    "params.local_min_distance": 0.0,
    "params.local_min_period": 0.0,
    "params.local_min_yaw": 0.0,
    "params.sensor_reliable": True,
}


def masters(leg) -> list[Segment]:
    return list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start"))


class Robot:
    """GPS fixes and local poses at RATE; ``sent`` holds the fixes' latitudes."""

    def __init__(self, ros):
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import NavSatFix

        self.types = NavSatFix, PoseStamped
        self.fix = ros.publisher(NavSatFix, "/gps_fix")
        self.local = ros.publisher(PoseStamped, "/local_pose")
        for publisher in (self.fix, self.local):
            ros.wait_subscribed(publisher)
        self.sent: list[float] = []

    def drive(self, seconds: float) -> None:
        NavSatFix, PoseStamped = self.types  # noqa: N806 - the message classes
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            step = len(self.sent)
            now = time.time()
            f = NavSatFix(latitude=50.0 + step * 1e-5, longitude=8.0)
            f.status.status, f.status.service = 0, 1  # a fix (Jazzy's default is unknown)
            f.header.stamp.sec, f.header.stamp.nanosec = int(now), int(now % 1 * 1e9)
            self.fix.publish(f)
            p = PoseStamped()
            p.header.frame_id, p.header.stamp = "map", f.header.stamp
            p.pose.position.x = float(step)
            p.pose.orientation.w = math.cos(0.0)
            self.local.publish(p)
            self.sent.append(f.latitude)
            time.sleep(1.0 / RATE)


def track(segment) -> list[float]:
    return [p.point.y for p in segment.poses.order_by("robot_stamp", "received", "id")]


@pytest.mark.parametrize("wait", [2.0, 30.0], ids=["mode_after_the_wait", "mode_within_the_wait"])
def test_a_robot_that_says_its_mode_only_on_change_loses_nothing(
    ros, start_collector, robot_leg, wait
):
    from std_msgs.msg import Bool

    start_collector(params={"params.unknown_mode_wait": wait, **UNTHINNED})
    mode = ros.publisher(Bool, "/robot_mode")  # volatile: no late joiner hears it
    ros.wait_subscribed(mode)
    robot = Robot(ros)
    assert ros.set_logging(True).success
    sent, drive = robot.sent, robot.drive

    drive(BEFORE_SWITCH)
    before = len(sent)
    said = time.time()
    mode.publish(Bool(data=True))  # its first mode message: AUTO
    drive(1.5)
    mode.publish(Bool(data=False))  # ITO
    drive(1.0)
    wait_for(lambda: Pose.objects.count() >= len(sent), 20, what="every fix sent")
    assert ros.set_logging(False).success

    found = masters(robot_leg)
    # The robot was connected and silent: its first mode message is a switch, in the wait or not.
    assert [m.segment_type_id for m in found] == ["unknown", "auto", "ito"]
    unknown, auto = found[0], found[1]
    stored = track(unknown)
    # Every fix and local pose sent before the first mode message has no known mode.
    assert stored == pytest.approx(sent[:before])
    assert LocalPose.objects.filter(segment=unknown).count() == before
    # AUTO's track starts at the last pose before it, as at every switch, and no earlier.
    assert not LocalPose.objects.filter(segment=auto, x__lt=before - 1).exists()
    # AUTO starts when the robot said it (its DDS send time), not at the first position.
    assert abs(auto.start.timestamp() - said) < 0.05

    figures = event_statistics(robot_leg.shift.test_event).overall
    assert figures.unknown_seconds == (auto.start - unknown.start).total_seconds()
    assert 0 < figures.unknown_seconds <= BEFORE_SWITCH + 1.0
    path = [(8.0, y) for y in stored] + [(auto.start_position.x, auto.start_position.y)]
    assert figures.unknown_distance == pytest.approx(gps_path_length(path), rel=1e-6)
    assert figures.unknown_distance > 0


OBSTACLE = "/obstacle"
REASONS = f"""
window: 2.0
rules:
  - {{topic: {OBSTACLE}, type: std_msgs/msg/Bool, field: data, values: [true], reason: safety}}
"""


def test_a_collector_started_late_keeps_the_auto_driving_before_a_switch_as_unknown(
    ros, start_collector, robot_leg
):
    from std_msgs.msg import Bool

    # The robot drives in AUTO and says so once, before any collector listens.
    mode = ros.publisher(Bool, "/robot_mode")  # volatile, only on change
    obstacle = ros.publisher(Bool, OBSTACLE)
    mode.publish(Bool(data=True))
    start_collector(
        params={"params.unknown_mode_wait": 5.0, "params.reason_rules": REASONS, **UNTHINNED}
    )
    for publisher in (mode, obstacle):
        ros.wait_subscribed(publisher)
    robot = Robot(ros)
    assert ros.set_logging(True).success
    robot.drive(2.5)
    # An obstacle seen and gone again just before the driver takes over.
    obstacle.publish(Bool(data=True))
    robot.drive(0.3)
    obstacle.publish(Bool(data=False))
    robot.drive(0.2)
    before = len(robot.sent)
    switched = time.time()
    mode.publish(Bool(data=False))  # ITO
    robot.drive(1.0)
    # Stored once a repeat can no longer make it a periodic mode (the wait after
    # it), while logging goes on.
    wait_for(lambda: len(masters(robot_leg)) == 2, 20, what="the switch stored")
    assert ros.set_logging(False).success
    wait_for(lambda: Pose.objects.count() >= len(robot.sent), 20, what="every fix sent")

    unknown, ito = masters(robot_leg)
    assert (unknown.segment_type_id, ito.segment_type_id) == ("unknown", "ito")
    assert track(unknown) == pytest.approx(robot.sent[:before])
    # ITO's track goes on from the last fix before the switch.
    assert track(ito) == pytest.approx(robot.sent[before - 1 :])
    # The switch at its real time, and the reason rules asked then: the obstacle
    # ended 0.2 s before it, within the rule's window.
    assert abs(ito.start.timestamp() - switched) < 0.05
    [takeover] = ito.children.all()
    assert (takeover.suggested_reason_id, takeover.ito_reason_id) == ("safety", "unassigned")
    figures = event_statistics(robot_leg.shift.test_event).overall
    assert figures.unknown_seconds == pytest.approx(3.0, abs=0.5)
    assert figures.manual_distance > 0 and figures.auto_distance == 0


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_collector_stopped_while_it_waits_for_the_first_mode_stores_what_it_held(
    ros, start_collector, robot_leg, sig
):
    collector = start_collector(params={"params.unknown_mode_wait": 30.0, **UNTHINNED})
    robot = Robot(ros)
    assert ros.set_logging(True).success
    robot.drive(2.0)

    def heard(name: str) -> int:
        inputs = Collector.objects.get(name="collector").inputs or {}
        return inputs.get(name, {}).get("count", 0)

    sent = len(robot.sent)
    wait_for(
        lambda: heard("gps_fix") >= sent and heard("local_pose") >= sent,
        what="every fix and pose heard",
    )
    assert masters(robot_leg) == []  # held in memory: no mode yet, the wait goes on
    assert collector.stop(sig) == 0, collector.output()

    # Stored under a master of unknown mode, left open like any segment at a clean stop.
    [master] = masters(robot_leg)
    assert (master.segment_type_id, master.end) == ("unknown", None)
    assert track(master) == pytest.approx(robot.sent)
    assert LocalPose.objects.filter(segment=master).count() == sent
