"""A fast GPS over real ROS 2: with thinning off every fix becomes a row."""

import time

import pytest

from events.models import Segment
from telemetry.models import Pose
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]

BURST = 1500


def test_a_burst_of_fixes_is_stored_without_loss(ros, start_collector, robot_leg):
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool

    start_collector(
        params={
            "params.sensor_reliable": True,
            "params.pose_min_distance": 0.0,
            "params.pose_min_period": 0.0,
        },
        args=["--start-logging"],
    )
    mode = ros.publisher(Bool, "/robot_mode")
    # The publisher keeps the whole burst, so the reliable protocol can repeat
    # what the transport dropped; what is lost after that is the collector's.
    fix_publisher = ros.publisher(
        NavSatFix, "/gps_fix", QoSProfile(depth=BURST, reliability=ReliabilityPolicy.RELIABLE)
    )
    for pub in (mode, fix_publisher):
        ros.wait_subscribed(pub)
    mode.publish(Bool(data=False))
    master = wait_for(
        lambda: Segment.objects.filter(leg=robot_leg, parent__isnull=True).first(),
        what="the ITO master",
    )
    fix = NavSatFix()
    fix.status.status = 0
    start = time.time()
    # 1.5 s of a 1 kHz receiver, sent as fast as this process can: harder
    # than the receiver itself, which spreads them over 1.5 s.
    for i in range(BURST):
        t = start + i / 1000
        fix.header.stamp.sec, fix.header.stamp.nanosec = int(t), int(t % 1 * 1e9)
        fix.latitude, fix.longitude = 50.6 + i * 1e-6, 7.1
        fix_publisher.publish(fix)
    wait_for(
        lambda: Pose.objects.filter(segment=master).count() >= BURST,
        60,
        what=f"{BURST} stored fixes",
    )
    points = Pose.objects.filter(segment=master).values_list("point", flat=True)
    assert sorted(round((p.y - 50.6) * 1e6) for p in points) == list(range(BURST))
