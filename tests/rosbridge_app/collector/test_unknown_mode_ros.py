"""A robot that says its mode only on change, without a latched topic, over DDS:
what it drove before its first switch is stored, and the statistics say how
much of it had no known mode (collector/unknown_mode.py); a collector stopped
while it waits for the first mode stores what it held."""

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


@pytest.mark.parametrize(
    ("wait", "modes"),
    [(2.0, ["unknown", "auto", "ito"]), (30.0, ["auto", "ito"])],
    ids=["mode_after_the_wait", "mode_within_the_wait"],
)
def test_a_robot_that_says_its_mode_only_on_change_loses_nothing(
    ros, start_collector, robot_leg, wait, modes
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
    mode.publish(Bool(data=True))  # its first word: AUTO
    drive(1.5)
    mode.publish(Bool(data=False))  # ITO
    drive(1.0)
    wait_for(lambda: Pose.objects.count() >= len(sent), 20, what="every fix sent")
    assert ros.set_logging(False).success

    found = masters(robot_leg)
    assert [m.segment_type_id for m in found] == modes
    first = found[0]
    stored = track(first)
    # Every fix and local pose sent before the first mode message is in the first segment.
    assert stored[:before] == pytest.approx(sent[:before])
    assert LocalPose.objects.filter(segment=first, x__lt=before).count() == before

    figures = event_statistics(robot_leg.shift.test_event).overall
    if wait < BEFORE_SWITCH:
        unknown, auto = found[0], found[1]
        assert figures.unknown_seconds == (auto.start - unknown.start).total_seconds()
        assert 0 < figures.unknown_seconds <= BEFORE_SWITCH + 1.0
        path = [(8.0, y) for y in stored] + [(auto.start_position.x, auto.start_position.y)]
        assert figures.unknown_distance == pytest.approx(gps_path_length(path), rel=1e-6)
        assert figures.unknown_distance > 0
    else:
        assert (figures.unknown_seconds, figures.unknown_distance) == (0.0, 0.0)


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
