"""ftt_mode_publisher as a process: joystick and navigation commands → robot mode."""

import time

import pytest

from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]


def test_manual_while_driving_then_auto_after_the_timeout(ros, procs):
    from geometry_msgs.msg import TwistStamped
    from std_msgs.msg import Bool

    procs.start(
        "ftt_mode_publisher", "--joy-timeout", "0.5", "--period", "0.2", name="mode_publisher"
    )
    modes = []
    ros.node.create_subscription(Bool, "robot_mode", lambda m: modes.append(m.data), 100)
    joy = ros.publisher(TwistStamped, "joy_cmd_vel")
    nav = ros.publisher(TwistStamped, "nav_cmd_vel")
    ros.wait_subscribed(joy, 30)
    ros.wait_subscribed(nav)
    driving = TwistStamped()
    driving.twist.linear.x = 0.5
    idle = TwistStamped()
    nav.publish(idle)
    wait_for(lambda: modes and modes[-1] is True, what="auto from navigation")
    # The operator drives for 1.5 s while navigation keeps sending.
    end = time.monotonic() + 1.5
    while time.monotonic() < end:
        joy.publish(driving)
        nav.publish(idle)
        time.sleep(0.05)
    wait_for(lambda: modes[-1] is False, what="manual")
    # Never back to auto while the operator was still driving (the original
    # timed out from the first joystick command and flipped after 0.5 s).
    assert True not in modes[modes.index(False) :]
    start = len(modes)
    for _ in range(5):  # 0.25 s: still within the timeout after the last joystick command
        nav.publish(idle)
        time.sleep(0.05)
    assert True not in modes[start:]
    time.sleep(0.4)
    nav.publish(idle)
    wait_for(lambda: modes[-1] is True, what="auto after the timeout")
