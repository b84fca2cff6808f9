"""manage.py ftt_play_bag: replay a ROS 1 or ROS 2 bag into live ROS 2 topics."""

import time
from pathlib import Path

import rclpy
from django.core.management.base import BaseCommand
from rclpy.executors import ExternalShutdownException

from rosbridge_app.collector.player import BagPlayer


class Command(BaseCommand):
    help = "Publish a bag's messages at the recorded pace (or faster with --rate)."

    def add_arguments(self, parser):
        parser.add_argument("bag", type=Path, help="ROS 1 .bag, or a ROS 2 bag directory.")
        parser.add_argument(
            "--rate",
            type=float,
            default=1.0,
            help="Speed factor (2 = twice as fast; 0 = as fast as possible).",
        )
        parser.add_argument("--prefix", default="", help="Prepend to every topic name.")
        parser.add_argument(
            "--wait-for",
            nargs="*",
            default=[],
            metavar="TOPIC",
            help="Wait until these bag topics have a subscriber.",
        )
        parser.add_argument("--wait-timeout", type=float, default=30.0)
        parser.add_argument(
            "--linger",
            type=float,
            default=1.0,
            help="Seconds to stay up after the last message (delivery).",
        )

    def handle(self, *args, **o):

        rclpy.init()
        player = BagPlayer(o["bag"], rate=o["rate"], prefix=o["prefix"])
        try:
            if o["wait_for"] and not player.wait_for_subscribers(o["wait_for"], o["wait_timeout"]):
                raise SystemExit(f"no subscriber on {o['wait_for']} after {o['wait_timeout']} s")
            started = time.monotonic()
            self.stdout.write(f"playing {o['bag']} ({player.duration:.1f} s) at ×{o['rate']}")
            count = player.play(should_stop=lambda: not rclpy.ok())
            time.sleep(o["linger"])
            self.stdout.write(f"played {count} messages in {time.monotonic() - started:.1f} s")
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            player.destroy_node()
            rclpy.try_shutdown()
