"""A simulated robot over real ROS 2 (``manage.py ftt_simulate``).

It drives around a circle near a configurable origin and publishes what a
real robot would: the mode (switching between manual and autonomous every
``switch_every`` seconds), GPS fixes, TF map→odom→base_link (+ a static
base_link→gps_link), a latched occupancy grid and camera frames (raw rgb8 on
``image``, or JPEG on ``image_compressed``).
"""

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CompressedImage, Image, NavSatFix, NavSatStatus
from tf2_msgs.msg import TFMessage

from rosbridge_app.collector import modes

EARTH_RADIUS = 6_371_008.8


@dataclass
class SimConfig:
    latitude: float = 50.6160
    longitude: float = 7.1285
    radius: float = 20.0
    speed: float = 1.5
    switch_every: float = 20.0
    first_mode: str = modes.ITO  # the mode it starts in (manual, as a robot leaves the depot)
    mode_type: str = modes.BOOL
    mode_rate: float = 1.0
    gps_rate: float = 10.0
    tf_rate: float = 20.0
    camera_rate: float = 5.0
    camera_width: int = 640
    camera_height: int = 480
    camera_format: str = "raw"  # "raw": Image rgb8 on image; "jpeg": CompressedImage
    map_size: int = 400
    map_resolution: float = 0.1
    map_rate: float = 0.0  # 0: publish once (latched); else republish a changed map
    prefix: str = ""  # topic prefix, e.g. a robot namespace


def _stamp(msg_stamp, t: float) -> None:
    msg_stamp.sec = int(t)
    msg_stamp.nanosec = int((t - int(t)) * 1e9)


class SimulatedRobot(Node):
    def __init__(
        self,
        config: SimConfig,
        name: str = "ftt_simulated_robot",
        clock: Callable[[], float] = time.time,
        context=None,
    ):
        """``clock``: the robot's time; a benchmark drives it faster than real time.
        ``context``: an rclpy context of its own (a test's), else the default one."""
        super().__init__(name, context=context)
        self.c = config
        self.clock = clock
        self.t0 = clock()
        p = config.prefix.rstrip("/")
        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self.pub_mode = self.create_publisher(
            modes.message_type(config.mode_type), f"{p}/robot_mode", 10
        )
        self.pub_fix = self.create_publisher(NavSatFix, f"{p}/gps_fix", 50)
        # Transforms in the robot's namespace too: two robots on one /tf share the
        # frame names (map, base_link) and garble each other's local track.
        self.pub_tf = self.create_publisher(TFMessage, f"{p}/tf", 100)
        self.pub_tf_static = self.create_publisher(TFMessage, f"{p}/tf_static", latched)
        self.pub_map = self.create_publisher(OccupancyGrid, f"{p}/map", latched)
        if config.camera_format == "jpeg":
            self.pub_image = self.create_publisher(CompressedImage, f"{p}/image_compressed", 5)
            self._jpegs = self._make_jpegs()
        else:
            self.pub_image = self.create_publisher(Image, f"{p}/image", 5)
        self.counts = {"mode": 0, "gps": 0, "tf": 0, "image": 0, "map": 0}
        self.map_version = 0
        self._grid = self._make_grid()
        self._publish_static()
        self.publish_map()

    def start(self, wait_for_subscriber: float = 0.0) -> None:
        """Start publishing; first wait (up to the given seconds) until someone
        listens to the GPS, so that a measurement does not count discovery time."""
        end = time.monotonic() + wait_for_subscriber
        while time.monotonic() < end and self.pub_fix.get_subscription_count() == 0:
            time.sleep(0.05)
        self.t0 = self.clock()
        c = self.c
        for rate, fn in (
            (c.mode_rate, self.publish_mode),
            (c.gps_rate, self.publish_fix),
            (c.tf_rate, self.publish_tf),
            (c.camera_rate, self.publish_image),
            (c.map_rate, self.publish_map),
        ):
            if rate > 0:
                self.create_timer(1.0 / rate, fn)

    # --- the drive ----------------------------------------------------------------------

    def elapsed(self) -> float:
        return self.clock() - self.t0

    def mode(self) -> str:
        phase = int(self.elapsed() // self.c.switch_every) if self.c.switch_every > 0 else 0
        other = modes.AUTO if self.c.first_mode == modes.ITO else modes.ITO
        return self.c.first_mode if phase % 2 == 0 else other

    def position(self, t: float | None = None) -> tuple[float, float, float]:
        """x, y (metres east/north of the circle's centre) and heading."""
        t = self.elapsed() if t is None else t
        angle = self.c.speed * t / self.c.radius
        x, y = self.c.radius * math.cos(angle), self.c.radius * math.sin(angle)
        return x, y, angle + math.pi / 2

    def lat_lon(self, x: float, y: float) -> tuple[float, float]:
        lat = self.c.latitude + math.degrees(y / EARTH_RADIUS)
        lon = self.c.longitude + math.degrees(
            x / (EARTH_RADIUS * math.cos(math.radians(self.c.latitude)))
        )
        return lat, lon

    # --- publishers ---------------------------------------------------------------------

    def publish_mode(self) -> None:
        self.pub_mode.publish(modes.make_message(self.c.mode_type, self.mode()))
        self.counts["mode"] += 1

    def publish_fix(self) -> None:
        x, y, _ = self.position()
        lat, lon = self.lat_lon(x, y)
        msg = NavSatFix()
        _stamp(msg.header.stamp, self.clock())
        msg.header.frame_id = "gps_link"
        msg.status.status = NavSatStatus.STATUS_FIX
        msg.status.service = NavSatStatus.SERVICE_GPS
        msg.latitude, msg.longitude, msg.altitude = lat, lon, 120.0
        msg.position_covariance = [0.25, 0.0, 0.0, 0.0, 0.25, 0.0, 0.0, 0.0, 1.0]
        msg.position_covariance_type = NavSatFix.COVARIANCE_TYPE_DIAGONAL_KNOWN
        self.pub_fix.publish(msg)
        self.counts["gps"] += 1

    def _transform(self, parent, child, x, y, yaw, t) -> TransformStamped:
        tf = TransformStamped()
        _stamp(tf.header.stamp, t)
        tf.header.frame_id, tf.child_frame_id = parent, child
        tf.transform.translation.x, tf.transform.translation.y = x, y
        tf.transform.rotation.z, tf.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        return tf

    def publish_tf(self) -> None:
        now = self.clock()
        x, y, yaw = self.position(now - self.t0)
        # odom drifts slowly away from map, as real odometry does.
        drift = 0.01 * (now - self.t0)
        msg = TFMessage(
            transforms=[
                self._transform("map", "odom", drift, 0.0, 0.0, now),
                self._transform("odom", "base_link", x - drift, y, yaw, now),
            ]
        )
        self.pub_tf.publish(msg)
        self.counts["tf"] += 1

    def _publish_static(self) -> None:
        tf = self._transform("base_link", "gps_link", 0.2, 0.0, 0.0, self.clock())
        self.pub_tf_static.publish(TFMessage(transforms=[tf]))

    def _make_grid(self) -> np.ndarray:
        n = self.c.map_size
        grid = np.full((n, n), -1, dtype=np.int8)
        yy, xx = np.mgrid[0:n, 0:n]
        r = np.hypot(xx - n / 2, yy - n / 2) * self.c.map_resolution
        grid[r < self.c.radius + 5] = 0
        grid[(r > self.c.radius + 4) & (r < self.c.radius + 5)] = 100
        return grid

    def publish_map(self) -> None:
        n = self.c.map_size
        if self.map_version:
            # A changed map each time: the robot keeps exploring.
            self._grid[self.map_version % n, :8] = 100
        self.map_version += 1
        msg = OccupancyGrid()
        _stamp(msg.header.stamp, self.clock())
        msg.header.frame_id = "map"
        msg.info.width = msg.info.height = n
        msg.info.resolution = self.c.map_resolution
        msg.info.origin.position.x = msg.info.origin.position.y = -n * self.c.map_resolution / 2
        msg.info.origin.orientation.w = 1.0
        msg.data = self._grid.ravel().tobytes()
        self.pub_map.publish(msg)
        self.counts["map"] += 1

    def _picture(self, t: float) -> np.ndarray:
        w, h = self.c.camera_width, self.c.camera_height
        img = np.zeros((h, w, 3), dtype=np.uint8)
        img[:, :, 0] = 200  # red sky: lets a test check the colour order
        img[h // 2 :, :, 1] = 120
        img[h // 2 :, :, 0] = 60
        x = int((t * 50) % w)
        img[:, max(0, x - 5) : x + 5, 2] = 255
        return img

    def _make_jpegs(self) -> list[bytes]:
        # Encoded once: the robot's CPU should go to publishing, not to encoding.
        # Sensor noise makes the files as large as a real camera's (~60 kB),
        # which a flat synthetic picture would not be.
        noise = np.random.default_rng(1).normal(
            0, 4, (self.c.camera_height, self.c.camera_width, 3)
        )
        frames = []
        for i in range(20):
            img = np.clip(self._picture(i * 0.5) + noise, 0, 255).astype(np.uint8)
            data = cv2.imencode(".jpg", cv2.cvtColor(img, cv2.COLOR_RGB2BGR))[1]
            frames.append(data.tobytes())
        return frames

    def publish_image(self) -> None:
        if self.c.camera_format == "jpeg":
            msg = CompressedImage(format="jpeg")
            msg.data = self._jpegs[self.counts["image"] % len(self._jpegs)]
        else:
            w, h = self.c.camera_width, self.c.camera_height
            msg = Image()
            msg.height, msg.width, msg.encoding = h, w, "rgb8"
            msg.step = w * 3
            msg.data = self._picture(self.elapsed()).tobytes()
        _stamp(msg.header.stamp, self.clock())
        msg.header.frame_id = "camera"
        self.pub_image.publish(msg)
        self.counts["image"] += 1
