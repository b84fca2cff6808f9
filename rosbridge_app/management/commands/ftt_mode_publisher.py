"""manage.py ftt_mode_publisher: robot mode from navigation and joystick commands.

The seeds' robotModePublisher: a non-zero joystick command (TwistStamped)
means manual at once; navigation commands mean autonomous again once the
*last* joystick command is ``--joy-timeout`` seconds old.  The mode is
published every ``--period`` seconds and at once when it changes.
"""

import time

import rclpy
from django.core.management.base import BaseCommand
from geometry_msgs.msg import TwistStamped
from rclpy.executors import ExternalShutdownException

from rosbridge_app.collector.modes import ModeDecider, is_moving, make_message, message_type


class Command(BaseCommand):
    help = "Publish the robot mode derived from joystick and navigation velocity commands."

    def add_arguments(self, parser):
        parser.add_argument("--joy-topic", default="joy_cmd_vel")
        parser.add_argument("--nav-topic", default="nav_cmd_vel")
        parser.add_argument("--mode-topic", default="robot_mode")
        parser.add_argument("--mode-type", choices=("bool", "industrial"), default="bool")
        parser.add_argument("--joy-timeout", type=float, default=0.5)
        parser.add_argument("--period", type=float, default=1.0)

    def handle(self, *args, **o):

        rclpy.init()
        node = rclpy.create_node("ftt_mode_publisher")
        decider = ModeDecider(o["joy_timeout"])
        pub = node.create_publisher(message_type(o["mode_type"]), o["mode_topic"], 10)
        state = {"published": None}

        def publish(force=False):
            mode = decider.mode
            if mode is not None and (force or mode != state["published"]):
                pub.publish(make_message(o["mode_type"], mode))
                state["published"] = mode

        def on_joy(msg):
            try:
                decider.joystick(is_moving(msg.twist), time.monotonic())
                publish()
            except Exception as exc:
                node.get_logger().warning(f"ignored a joystick message: {exc}")

        def on_nav(msg):
            try:
                decider.navigation(time.monotonic())
                publish()
            except Exception as exc:
                node.get_logger().warning(f"ignored a navigation message: {exc}")

        node.create_subscription(TwistStamped, o["joy_topic"], on_joy, 10)
        node.create_subscription(TwistStamped, o["nav_topic"], on_nav, 10)
        node.create_timer(o["period"], lambda: publish(force=True))
        try:
            rclpy.spin(node)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            node.destroy_node()
            rclpy.try_shutdown()
