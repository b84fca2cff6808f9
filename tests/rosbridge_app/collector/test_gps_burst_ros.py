"""A fast GPS over real ROS 2: with thinning off every fix becomes a row."""

import time

import pytest

from telemetry.models import Pose
from tests.rosbridge_app.collector.conftest import logging_robot
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]

BURST = 1500


def test_a_burst_of_fixes_is_stored_without_loss(ros, start_collector, robot_leg):
    from sensor_msgs.msg import NavSatFix

    _, fix_publisher, master = logging_robot(ros, start_collector, robot_leg, BURST)
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
