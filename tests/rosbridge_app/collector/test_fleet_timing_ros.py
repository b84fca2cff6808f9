"""A starved collector stores the robot's switch time; fixes the robot did not
send show in its heartbeat as publisher gaps, not as lost."""

import time

import pytest

from events.models import Segment
from rosbridge_app.models import Collector
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]


def stamp(header, t: float) -> None:
    header.stamp.sec, header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))


def test_switch_time_is_when_the_robot_sent_it_and_publisher_gaps_are_counted(
    ros, start_collector, robot_leg
):
    from industrial_msgs.msg import RobotMode
    from sensor_msgs.msg import NavSatFix

    start_collector(params={"params.robot_mode_type": "industrial"})
    mode = ros.publisher(RobotMode, "/robot_mode")
    fix = ros.publisher(NavSatFix, "/gps_fix", 100)
    for pub in (mode, fix):
        ros.wait_subscribed(pub)
    # industrial_msgs/RobotMode has no header: the switch is placed at the
    # time the robot sent it, within the interval since its last message.
    mode.publish(RobotMode(val=RobotMode().MANUAL))
    assert ros.set_logging(True).success
    wait_for(lambda: Segment.objects.filter(leg=robot_leg).exists(), what="the ITO master")

    t0 = time.time()
    for i in range(40):
        if i in (20, 21, 22):  # three beats the robot skipped
            continue
        f = NavSatFix(latitude=50.6 + i * 1e-6, longitude=7.1)
        stamp(f.header, t0 + i * 0.05)
        fix.publish(f)
        time.sleep(0.05)
    sent = time.time()
    mode.publish(RobotMode(val=RobotMode().AUTO))
    master = wait_for(
        lambda: Segment.objects.filter(leg=robot_leg, segment_type_id="auto").first(),
        what="the AUTO master",
    )
    assert sent <= master.start.timestamp() < sent + 0.05
    assert master.robot_stamp == master.start
    assert master.start_uncertainty >= sent - t0 > 1.5
    status = wait_for(
        lambda: Collector.objects.filter(name="collector", inputs__gps_fix__count__gte=37).first(),
        5,
        what="the heartbeat",
    )
    gps = status.inputs["gps_fix"]
    assert (gps["publisher_gaps"], gps["dropped"]) == (3, 0)
    assert gps["rate"] == pytest.approx(20, rel=0.05)
    robot_leg.refresh_from_db()
    assert robot_leg.fixes_missed == 0  # nothing the robot sent was lost
