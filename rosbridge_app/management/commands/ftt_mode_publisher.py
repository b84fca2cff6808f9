"""manage.py ftt_mode_publisher: robot mode from navigation and joystick commands.

The seeds' robotModePublisher: a non-zero joystick command (TwistStamped)
means manual at once; navigation commands mean autonomous again once the
*last* joystick command is ``--joy-timeout`` seconds old.  The mode is
published every ``--period`` seconds and at once when it changes.
"""

import time

import rclpy
from django.core.management.base import BaseCommand
from django.utils.translation import gettext as _
from geometry_msgs.msg import TwistStamped
from rclpy.executors import ExternalShutdownException

from rosbridge_app.collector.modes import ModeDecider, is_moving, make_message, message_type


class Command(BaseCommand):
    help = _("Publish the robot mode derived from joystick and navigation velocity commands.")

    def add_arguments(self, parser):
        add = parser.add_argument
        add("--joy-topic", default="joy_cmd_vel", help=_("Joystick velocity commands."))
        add("--nav-topic", default="nav_cmd_vel", help=_("Navigation velocity commands."))
        add("--mode-topic", default="robot_mode", help=_("Topic the mode is published on."))
        add(
            "--mode-type",
            choices=("bool", "industrial"),
            default="bool",
            help=_("Message type of the mode."),
        )
        add(
            "--joy-timeout",
            type=float,
            default=0.5,
            help=_("Seconds after the last joystick command until autonomous again."),
        )
        add("--period", type=float, default=1.0, help=_("Seconds between publications."))

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
                node.get_logger().warning(_("ignored a joystick message: %(exc)s") % {"exc": exc})

        def on_nav(msg):
            try:
                decider.navigation(time.monotonic())
                publish()
            except Exception as exc:
                node.get_logger().warning(_("ignored a navigation message: %(exc)s") % {"exc": exc})

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
