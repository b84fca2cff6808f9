"""Replays a bag into live ROS 2 topics (``manage.py ftt_play_bag``).

ROS 1 and ROS 2 bags alike: messages are read with rosbags and copied into
rclpy messages, then published at the recorded pace divided by ``rate``.
Latched topics (ROS 1 latching, ROS 2 transient-local) are published
transient-local.
"""

import logging
import time
from pathlib import Path

from django.utils.translation import gettext
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from rosbridge_app.collector.bag import bag_messages, latched, open_bag, rclpy_type, to_rclpy

log = logging.getLogger("ftt.player")


class BagPlayer(Node):
    def __init__(self, path: Path, *, rate: float = 1.0, prefix: str = ""):
        super().__init__("ftt_bag_player")
        self.path, self.rate, self.prefix = Path(path), rate, prefix.rstrip("/")
        self.publishers_: dict[str, object] = {}
        self.types: dict[str, type] = {}
        with open_bag(self.path) as reader:
            for c in reader.connections:
                if c.topic in self.publishers_:
                    continue
                cls = rclpy_type(c.msgtype)
                latched = _is_latched(c)
                qos = QoSProfile(
                    history=HistoryPolicy.KEEP_LAST,
                    depth=1 if latched else 1000,
                    reliability=ReliabilityPolicy.RELIABLE,
                    durability=(
                        DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE
                    ),
                )
                self.types[c.topic] = cls
                self.publishers_[c.topic] = self.create_publisher(cls, self.topic(c.topic), qos)
            self.duration = (reader.end_time - reader.start_time) / 1e9

    def topic(self, name: str) -> str:
        return f"{self.prefix}/{name.lstrip('/')}" if self.prefix else name

    def wait_for_subscribers(self, topics: list[str], timeout: float) -> bool:
        """Publishers of on-change topics must see their subscriber first."""
        end = time.monotonic() + timeout
        wanted = [t for t in topics if t in self.publishers_]
        while time.monotonic() < end:
            if all(self.publishers_[t].get_subscription_count() > 0 for t in wanted):
                return True
            time.sleep(0.05)
        return False

    def play(self, should_stop=lambda: False) -> int:
        count = 0
        wall0 = bag0 = None
        for m in bag_messages(self.path, set(self.publishers_)):
            if should_stop():
                break
            if wall0 is None:
                wall0, bag0 = time.monotonic(), m.time_ns
            if self.rate > 0:
                delay = wall0 + (m.time_ns - bag0) / 1e9 / self.rate - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            try:
                self.publishers_[m.topic].publish(to_rclpy(m.msg, self.types[m.topic]))
                count += 1
            except Exception as exc:
                log.warning(
                    gettext("could not publish a %s message on %s: %s"), m.msgtype, m.topic, exc
                )
        return count


def _is_latched(connection) -> bool:
    return latched(connection)
