"""manage.py ftt_play_bag: replay a ROS 1 or ROS 2 bag into live ROS 2 topics."""

import time
from pathlib import Path

import rclpy
from django.core.management.base import BaseCommand
from django.utils.formats import number_format
from django.utils.translation import gettext as _
from rclpy.executors import ExternalShutdownException

from common.numbers import short
from rosbridge_app.collector.player import BagPlayer


class Command(BaseCommand):
    help = _("Publish a bag's messages at the recorded pace (or faster with --rate).")

    def add_arguments(self, parser):
        parser.add_argument("bag", type=Path, help=_("ROS 1 .bag, or a ROS 2 bag directory."))
        parser.add_argument(
            "--rate",
            type=float,
            default=1.0,
            help=_("Speed factor (2 = twice as fast; 0 = as fast as possible)."),
        )
        parser.add_argument("--prefix", default="", help=_("Prepend to every topic name."))
        parser.add_argument(
            "--wait-for",
            nargs="*",
            default=[],
            metavar="TOPIC",
            help=_("Wait until these bag topics have a subscriber."),
        )
        parser.add_argument(
            "--wait-timeout", type=float, default=30.0, help=_("Seconds to wait for them.")
        )
        parser.add_argument(
            "--linger",
            type=float,
            default=1.0,
            help=_("Seconds to stay up after the last message (delivery)."),
        )

    def handle(self, *args, **o):

        rclpy.init()
        player = BagPlayer(o["bag"], rate=o["rate"], prefix=o["prefix"])
        try:
            if o["wait_for"] and not player.wait_for_subscribers(o["wait_for"], o["wait_timeout"]):
                raise SystemExit(
                    _("No subscriber on %(topics)s after %(seconds)s s.")
                    % {
                        "topics": ", ".join(o["wait_for"]),
                        "seconds": short(o["wait_timeout"]),
                    }
                )
            started = time.monotonic()
            self.stdout.write(
                _("playing %(bag)s (%(seconds)s s) at ×%(rate)s")
                % {
                    "bag": o["bag"],
                    "seconds": number_format(player.duration, 1),
                    "rate": short(o["rate"]),
                }
            )
            count = player.play(should_stop=lambda: not rclpy.ok())
            time.sleep(o["linger"])
            self.stdout.write(
                _("played %(count)s messages in %(seconds)s s")
                % {"count": count, "seconds": number_format(time.monotonic() - started, 1)}
            )
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            player.destroy_node()
            rclpy.try_shutdown()
