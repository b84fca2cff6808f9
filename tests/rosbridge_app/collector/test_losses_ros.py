"""Over DDS, the loss estimate tells a publisher that sent fewer messages than
its rate (nothing lost: publisher gaps) from messages the collector dropped
(a burst beyond its subscription's queue) (collector/losses.py)."""

import time

import pytest

from rosbridge_app.collector.inputs import POSITION_DEPTH
from rosbridge_app.models import Collector
from tests.rosbridge_app.collector.conftest import logging_robot
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]


def fix_at(i: int, t: float):
    from sensor_msgs.msg import NavSatFix

    fix = NavSatFix(latitude=50.6 + i * 1e-6, longitude=7.1)
    fix.status.status = 0
    fix.header.stamp.sec, fix.header.stamp.nanosec = int(t), int(round(t % 1 * 1e9))
    return fix


def heartbeat(received: int):
    """The first heartbeat that counts ``received`` GPS fixes."""
    return wait_for(
        lambda: Collector.objects.filter(
            name="collector", inputs__gps_fix__count__gte=received
        ).first(),
        30,
        what=f"a heartbeat with {received} fixes",
    )


def test_a_publisher_slower_than_its_rate_has_publisher_gaps_and_nothing_dropped(
    ros, start_collector, robot_leg
):
    collector, fixes, _ = logging_robot(ros, start_collector, robot_leg, 100)
    t0 = time.time()
    sent = 0
    for i in range(60):
        if i in (20, 21, 22, 40, 41):  # the loaded robot's timer skipped these beats
            continue
        fixes.publish(fix_at(i, t0 + i * 0.05))
        sent += 1
        time.sleep(0.05)
    inputs = heartbeat(sent).inputs["gps_fix"]
    assert (inputs["publisher_gaps"], inputs["dropped"]) == (5, 0)
    assert inputs["rate"] == pytest.approx(20, rel=0.05)
    # The log's ten-second report: the gaps under their own name, no drop.
    wait_for(lambda: "publisher gaps" in collector.output(), 20, what="the log's report")
    assert "dropped" not in collector.output()
    robot_leg.refresh_from_db()
    assert robot_leg.fixes_missed == 0  # the robot's track lost nothing the robot sent


BURST = 20 * POSITION_DEPTH


def test_a_burst_beyond_the_subscription_queue_is_counted_as_dropped(
    ros, start_collector, robot_leg
):
    collector, fixes, _ = logging_robot(ros, start_collector, robot_leg, BURST)
    t0 = time.time()
    # Twenty times the queue, as fast as this process can send: the reliable
    # publisher keeps every one, the collector's queue overflows.
    for i in range(BURST):
        fixes.publish(fix_at(i, t0 + i / 1000))

    def settled():
        row = Collector.objects.get(name="collector")
        info = (row.inputs or {}).get("gps_fix") or {}
        total = info.get("count", 0) + info.get("dropped", 0)
        return info if total >= BURST else None

    inputs = wait_for(settled, 60, what="every fix received or counted as dropped")
    # Every fix sent is either received or dropped, and the drops are not gaps.
    assert inputs["count"] + inputs["dropped"] == BURST
    assert inputs["dropped"] > 0 and inputs["publisher_gaps"] == 0
    wait_for(lambda: "dropped" in collector.output(), 20, what="the log's report")
    assert "publisher gaps" not in collector.output()
    robot_leg.refresh_from_db()
    assert robot_leg.fixes_missed == inputs["dropped"]
