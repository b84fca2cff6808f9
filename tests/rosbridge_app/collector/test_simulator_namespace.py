"""Two simulated robots started as docs/collector.md says keep their transforms
apart: each publishes /tf and /tf_static in its own namespace."""

import pytest

from tests.support.ros import DOMAIN_ID, requires_ros

pytestmark = requires_ros


@pytest.mark.parametrize(("prefix", "tf"), [("/robot1", "/robot1/tf"), ("", "/tf")])
def test_simulated_robot_publishes_transforms_in_its_namespace(prefix, tf):
    import rclpy
    from rclpy.context import Context

    from rosbridge_app.collector.simulator import SimConfig, SimulatedRobot

    context = Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID)
    try:
        robot = SimulatedRobot(SimConfig(prefix=prefix, map_size=10), context=context)
        assert robot.pub_tf.topic_name == tf
        assert robot.pub_tf_static.topic_name == f"{tf}_static"
        assert robot.pub_fix.topic_name == f"{prefix}/gps_fix"
        robot.destroy_node()
    finally:
        rclpy.shutdown(context=context)
