"""Bag imports of a ROS 2 recording holding every kind of data the collector stores.

The only real recording in the suite (tests/support/fkie.py) has modes and GPS and
nothing else, so the map, camera and local-pose paths of the importer were
never run on a bag.  These bags are written at test time with rosbags: every
value in them is known, so the rows FTT makes of them can be checked exactly.

The recording, 60 s from T0 (seconds after T0):
* the mode once a second at k + 0.5: AUTO for k < 20, ITO for k < 40, then
  AUTO again, so three masters start at 0.5, 20.5 and 40.5 and the repeats
  in between must not open any;
* a GPS fix at k + 0.1, a transform odom→base_link at k + 0.2 (map→odom is
  static, sent once at 0.0) and a PoseStamped at k + 0.25, for k = 0..60,
  each step far enough apart for the collector's thinning to keep it;
* the same occupancy grid at 1.7 and 31.7, camera frames at 10.3 and 30.3.
"""

import io
import shutil
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from django.core.management import CommandError, call_command
from PIL import Image as PilImage
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from events.models import Leg, Segment, Shift, TestEvent
from events.services import logs
from exchange.bag import import_bag
from rosbridge_app.collector.params import write_file
from telemetry.models import Image, LocalPose, MapImage, Pose

pytestmark = pytest.mark.django_db

ROS_INTERFACES = Path(__file__).resolve().parents[2] / "ros_interfaces"
ROBOT_MODE = "industrial_msgs/msg/RobotMode"
T0 = datetime(2024, 5, 6, 9, 0, tzinfo=UTC)
T0_NS = int(T0.timestamp()) * 1_000_000_000
LAST = 60  # the last second with a fix, a transform and a pose
END = 60.25  # the last message of the bag: the pose of second 60

# map→odom; the robot's position in the map is this plus odom→base_link.
ODOM_IN_MAP = (10.0, -4.0)
ROBOT_YAW = 0.3
GRID_WIDTH, GRID_HEIGHT, GRID_RESOLUTION = 4, 3, 0.25  # 0.25: exact as float32
GRID_ORIGIN = (-1.5, 2.25)
FREE, OCCUPIED, UNKNOWN = 0, 100, -1
# Row 0 is at the origin, i.e. the bottom of the picture.
GRID_ROWS = [
    [FREE, OCCUPIED, UNKNOWN, FREE],
    [FREE, FREE, OCCUPIED, OCCUPIED],
    [UNKNOWN, UNKNOWN, FREE, FREE],
]
# map_server's greys: free white, occupied black, unknown grey.
GREY = {FREE: 254, OCCUPIED: 0, UNKNOWN: 205}
CAMERA = {10.3: (200, 30, 60), 30.3: (20, 90, 220)}  # second → rgb8 colour
CAMERA_SIZE = (8, 6)


def mode_at(k: int) -> str:
    return "ito" if 20 <= k < 40 else "auto"


def fix_at(k: int) -> tuple[float, float]:
    """(longitude, latitude): about 1.3 m a second, beyond the 0.5 m thinning."""
    return 7.1 + k * 1e-5, 50.7 + k * 1e-5


def tf_at(k: int) -> tuple[float, float]:
    """odom→base_link translation."""
    return 0.5 * k, 0.25 * k


def tf_local_at(k: int) -> tuple[float, float]:
    dx, dy = tf_at(k)
    return ODOM_IN_MAP[0] + dx, ODOM_IN_MAP[1] + dy


def pose_at(k: int) -> tuple[float, float]:
    """The PoseStamped's position, elsewhere than TF's, so the source is visible."""
    return 3.0 - 0.5 * k, 0.75 * k


def at(second: float) -> datetime:
    return T0 + timedelta(seconds=second)


def typestore():
    store = get_typestore(Stores.ROS2_JAZZY)
    # RobotMode is no ROS 2 core message; FTT vendors its definition.
    text = (ROS_INTERFACES / "industrial_msgs" / "msg" / "RobotMode.msg").read_text()
    store.register(get_types_from_msg(text, ROBOT_MODE))
    return store


class Recording:
    def __init__(self):
        self.store = typestore()
        self.types = self.store.types
        self.messages: list[tuple[int, str, str, object]] = []

    def new(self, msgtype: str, **fields):
        return self.types[msgtype](**fields)

    def header(self, second: float, frame: str = ""):
        sec, nanosec = divmod(T0_NS + round(second * 1e9), 1_000_000_000)
        stamp = self.new("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec)
        return self.new("std_msgs/msg/Header", stamp=stamp, frame_id=frame)

    def add(self, topic: str, msgtype: str, second: float, msg) -> None:
        self.messages.append((T0_NS + round(second * 1e9), topic, msgtype, msg))

    def write(self, path: Path, storage: str) -> Path:
        plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
        connections = {}
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            for time_ns, topic, msgtype, msg in sorted(self.messages, key=lambda m: m[0]):
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, msgtype, typestore=self.store)
                writer.write(connections[topic], time_ns, self.store.serialize_cdr(msg, msgtype))
        return path

    # --- geometry ---------------------------------------------------------------------------

    def point(self, x: float, y: float):
        return self.new("geometry_msgs/msg/Point", x=x, y=y, z=0.0)

    def yaw(self, yaw: float):
        return self.new(
            "geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=np.sin(yaw / 2), w=np.cos(yaw / 2)
        )

    def transform(self, second: float, parent: str, child: str, x: float, y: float, yaw: float):
        translation = self.new("geometry_msgs/msg/Vector3", x=x, y=y, z=0.0)
        return self.new(
            "geometry_msgs/msg/TransformStamped",
            header=self.header(second, parent),
            child_frame_id=child,
            transform=self.new(
                "geometry_msgs/msg/Transform", translation=translation, rotation=self.yaw(yaw)
            ),
        )

    # --- messages ---------------------------------------------------------------------------

    def mode(self, kind: str, topic: str, second: float, mode: str) -> None:
        if kind == "bool":
            msgtype, msg = "std_msgs/msg/Bool", self.new("std_msgs/msg/Bool", data=mode == "auto")
        else:
            # industrial_msgs/RobotMode: MANUAL = 1, AUTO = 2.
            msgtype, msg = ROBOT_MODE, self.new(ROBOT_MODE, val=2 if mode == "auto" else 1)
        self.add(topic, msgtype, second, msg)

    def fix(self, second: float, lon: float, lat: float) -> None:
        msg = self.new(
            "sensor_msgs/msg/NavSatFix",
            header=self.header(second, "gps"),
            status=self.new("sensor_msgs/msg/NavSatStatus", status=0, service=1),
            latitude=lat,
            longitude=lon,
            altitude=120.0,
            position_covariance=np.zeros(9),
            position_covariance_type=0,
        )
        self.add("/gps_fix", "sensor_msgs/msg/NavSatFix", second, msg)

    def tf(self, topic: str, second: float, *transforms) -> None:
        msg = self.new("tf2_msgs/msg/TFMessage", transforms=list(transforms))
        self.add(topic, "tf2_msgs/msg/TFMessage", second, msg)

    def pose(self, second: float, frame: str, x: float, y: float, yaw: float) -> None:
        msg = self.new(
            "geometry_msgs/msg/PoseStamped",
            header=self.header(second, frame),
            pose=self.new(
                "geometry_msgs/msg/Pose", position=self.point(x, y), orientation=self.yaw(yaw)
            ),
        )
        self.add("/local_pose", "geometry_msgs/msg/PoseStamped", second, msg)

    def grid(self, second: float) -> None:
        info = self.new(
            "nav_msgs/msg/MapMetaData",
            map_load_time=self.header(0.0).stamp,
            resolution=GRID_RESOLUTION,
            width=GRID_WIDTH,
            height=GRID_HEIGHT,
            origin=self.new(
                "geometry_msgs/msg/Pose",
                position=self.point(*GRID_ORIGIN),
                orientation=self.yaw(0.0),
            ),
        )
        msg = self.new(
            "nav_msgs/msg/OccupancyGrid",
            header=self.header(0.0, "map"),
            info=info,
            data=np.array(GRID_ROWS, dtype=np.int8).ravel(),
        )
        self.add("/map", "nav_msgs/msg/OccupancyGrid", second, msg)

    def camera(self, second: float, rgb: tuple[int, int, int]) -> None:
        width, height = CAMERA_SIZE
        pixels = np.empty((height, width, 3), dtype=np.uint8)
        pixels[:, :] = rgb
        msg = self.new(
            "sensor_msgs/msg/Image",
            header=self.header(second, "camera"),
            height=height,
            width=width,
            encoding="rgb8",
            is_bigendian=0,
            step=width * 3,
            data=pixels.ravel(),
        )
        self.add("/image", "sensor_msgs/msg/Image", second, msg)


def write_bag(
    path: Path, *, mode: str = "bool", mode_topic: str = "/robot_mode", storage: str = "sqlite3"
) -> Path:
    rec = Recording()
    rec.tf("/tf_static", 0.0, rec.transform(0.0, "map", "odom", *ODOM_IN_MAP, 0.0))
    for k in range(LAST + 1):
        if k < LAST:
            rec.mode(mode, mode_topic, k + 0.5, mode_at(k))
        rec.fix(k + 0.1, *fix_at(k))
        rec.tf("/tf", k + 0.2, rec.transform(k + 0.2, "odom", "base_link", *tf_at(k), ROBOT_YAW))
        rec.pose(k + 0.25, "odom", *pose_at(k), 0.0)
    rec.grid(1.7)
    rec.grid(31.7)  # the same map again (a latched topic re-sent): not a second row
    for second, rgb in CAMERA.items():
        rec.camera(second, rgb)
    return rec.write(path, storage)


def masters() -> list[Segment]:
    return list(Segment.objects.filter(parent__isnull=True).order_by("start"))


# The fixes / local poses each master gets, as k of fix_at(k): a new master
# starts with the latest one, so neighbouring tracks share a point.
TRACKS = [range(0, 21), range(20, 41), range(40, 61)]


def assert_segments() -> list[Segment]:
    found = masters()
    assert [m.segment_type_id for m in found] == ["auto", "ito", "auto"]
    # The first segment starts at the first fix, before the first mode message at 0.5 s
    # (rosbridge_app/collector/unknown_mode.py).
    assert [(m.start, m.end) for m in found] == [
        (at(0.1), at(20.5)),
        (at(20.5), at(40.5)),
        (at(40.5), at(END)),
    ]
    # An ITO master always has its reason child, unassigned until an operator says.
    assert list(found[1].children.values_list("ito_reason_id", flat=True)) == ["unassigned"]
    assert not found[0].children.exists() and not found[2].children.exists()
    for master, track in zip(found, TRACKS, strict=True):
        assert (master.start_position.x, master.start_position.y) == fix_at(track[0])
    return found


def assert_gps(found: list[Segment]) -> None:
    for master, track in zip(found, TRACKS, strict=True):
        poses = list(master.poses.order_by("robot_stamp"))
        assert [(p.point.x, p.point.y) for p in poses] == [fix_at(k) for k in track]
        assert [p.robot_stamp for p in poses] == [at(k + 0.1) for k in track]
        assert {p.altitude for p in poses} == {120.0}


def assert_local(found: list[Segment], frame: str, position, second: float, yaw: float) -> None:
    for master, track in zip(found, TRACKS, strict=True):
        poses = list(master.local_poses.order_by("robot_stamp"))
        assert [(p.frame, p.x, p.y) for p in poses] == [(frame, *position(k)) for k in track]
        assert [p.robot_stamp for p in poses] == [at(k + second) for k in track]
        assert [p.yaw for p in poses] == pytest.approx([yaw] * len(track), abs=1e-12)
        start = (master.start_local_frame, master.start_local_x, master.start_local_y)
        assert start == (frame, *position(track[0]))


def assert_map() -> None:
    stored = MapImage.objects.get()
    assert stored.shift == Shift.objects.get()
    assert (stored.frame, stored.width, stored.height) == ("map", GRID_WIDTH, GRID_HEIGHT)
    assert (stored.resolution, stored.origin_x, stored.origin_y, stored.origin_yaw) == (
        GRID_RESOLUTION,
        *GRID_ORIGIN,
        0.0,
    )
    with stored.image.open("rb") as f, PilImage.open(io.BytesIO(f.read())) as png:
        assert png.size == (GRID_WIDTH, GRID_HEIGHT)
        greys = np.asarray(png.convert("L"))
    assert greys[::-1].tolist() == [[GREY[v] for v in row] for row in GRID_ROWS]


def decoded_colour(image: Image) -> np.ndarray:
    with image.image.open("rb") as f, PilImage.open(io.BytesIO(f.read())) as jpeg:
        assert jpeg.format == "JPEG"
        assert jpeg.size == CAMERA_SIZE
        return np.asarray(jpeg.convert("RGB")).reshape(-1, 3).astype(int)


def assert_camera(found: list[Segment]) -> None:
    # Each frame waits in the ring buffer for the next mode switch and goes to
    # the master that switch opens; the first master had no frame before it.
    auto, ito, auto_again = found
    assert not auto.images.exists()
    for master, second in ((ito, 10.3), (auto_again, 30.3)):
        image = master.images.get()
        assert image.robot_stamp == at(second)
        assert image.description == "Camera, 10.2 s before the mode switch"
        # JPEG is lossy; a flat colour survives it within a few levels.
        difference = np.abs(decoded_colour(image) - np.array(CAMERA[second]))
        assert difference.max() <= 3


def row_counts() -> dict:
    models = (TestEvent, Shift, Leg, Segment, Pose, LocalPose, MapImage, Image)
    return {m.__name__: m.objects.count() for m in models}


# --- tests ------------------------------------------------------------------------------------


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
@pytest.mark.parametrize("mode", ["bool", "industrial"])
def test_every_kind_of_data_becomes_rows(vehicle, media_root, tmp_path, mode, storage):
    bag = write_bag(tmp_path / "run", mode=mode, storage=storage)
    result = import_bag(bag, vehicle=vehicle)
    # Positions come from TF by default; the PoseStamped topic is ignored.
    assert result.added == {"Pose": 63, "LocalPose": 63, "MapImage": 1, "Image": 2}
    assert result.skipped == 0
    found = assert_segments()
    assert {m.leg for m in found} == {result.leg}
    assert_gps(found)
    assert_local(found, "map", tf_local_at, 0.2, ROBOT_YAW)
    assert_map()
    assert_camera(found)
    event = TestEvent.objects.get()
    assert (event.start, event.end) == (T0, at(END))
    assert result.leg.recording == "run"


def test_local_poses_from_pose_stamped_when_tf_is_off(vehicle, media_root, tmp_path):
    bag = write_bag(tmp_path / "run", mode="industrial")
    result = import_bag(bag, vehicle=vehicle, params={"params.use_tf": False})
    assert result.added["LocalPose"] == 63
    found = assert_segments()
    # The frame is the message's own, not params.map_frame.
    assert_local(found, "odom", pose_at, 0.25, 0.0)


def open_leg(vehicle) -> Leg:
    start = T0 - timedelta(hours=1)
    event = logs.create_test_event(at=start)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, at=start)
    return logs.create_leg(shift=shift, at=start)


@pytest.mark.parametrize("into", ["new test event", "open leg"])
@pytest.mark.parametrize("mode", ["bool", "industrial"])
def test_importing_the_same_bag_again_adds_nothing(vehicle, media_root, tmp_path, mode, into):
    # Into a new test event the second import meets a closed leg; into an open
    # leg only the rows' stable uids keep it from logging everything twice.
    leg = open_leg(vehicle) if into == "open leg" else None
    bag = write_bag(tmp_path / "run", mode=mode)
    first = import_bag(bag, vehicle=vehicle, leg=leg)
    before = row_counts()
    assert before == {
        "TestEvent": 1,
        "Shift": 1,
        "Leg": 1,
        "Segment": 4,  # three masters and the ITO master's reason child
        "Pose": 63,
        "LocalPose": 63,
        "MapImage": 1,
        "Image": 2,
    }
    assert_segments()
    again = import_bag(bag, vehicle=vehicle, leg=leg)
    assert again.added == {"Pose": 0, "LocalPose": 0, "MapImage": 0, "Image": 0}
    assert row_counts() == before
    assert again.leg == first.leg == Leg.objects.get()
    if leg is not None:
        leg.refresh_from_db()
        assert leg.end is None  # the user's leg is left open for more logging


def run_command(*args) -> str:
    out = io.StringIO()
    call_command("ftt_import_bag", *map(str, args), stdout=out, stderr=io.StringIO())
    return out.getvalue()


def test_bool_mode_on_a_renamed_topic_is_read_when_the_topic_is_given(
    vehicle, media_root, tmp_path
):
    bag = write_bag(tmp_path / "run", mode_topic="/husky/robot_mode")
    out = run_command(bag, "--vehicle", "husky", "--topic", "robot_mode=/husky/robot_mode")
    assert "3 master segments" in out
    assert "added 63 Pose, 63 LocalPose, 1 MapImage, 2 Image" in out
    assert_gps(assert_segments())


def test_bool_on_an_unconfigured_topic_is_no_mode(vehicle, media_root, tmp_path):
    # Any topic may carry a std_msgs/Bool; only the configured one is the mode. The
    # track is kept all the same, in one segment of unknown mode.
    bag = write_bag(tmp_path / "run", mode_topic="/husky/robot_mode")
    out = run_command(bag, "--vehicle", "husky")
    assert "1 master segments" in out
    (unknown,) = masters()
    assert (unknown.segment_type_id, unknown.start, unknown.end) == ("unknown", at(0.1), at(END))
    assert [(p.point.x, p.point.y) for p in unknown.poses.order_by("robot_stamp")] == [
        fix_at(k) for k in range(LAST + 1)
    ]
    assert MapImage.objects.count() == 1  # the map belongs to the shift, not to a segment


def test_a_bare_mcap_file_imports_as_its_bag_directory_does(vehicle, media_root, tmp_path):
    # A file alone, as the black box writes them or Foxglove saves them: rosbags
    # itself opens a ROS 2 bag only by its directory's metadata.yaml.
    (recorded,) = write_bag(tmp_path / "run", storage="mcap").glob("*.mcap")
    alone = tmp_path / "downloads" / "husky-run.mcap"
    alone.parent.mkdir()
    shutil.copyfile(recorded, alone)
    out = run_command(alone, "--vehicle", "husky")
    assert "3 master segments" in out
    assert "added 63 Pose, 63 LocalPose, 1 MapImage, 2 Image" in out
    found = assert_segments()
    assert_gps(found)
    assert_camera(found)
    assert sorted(p.name for p in alone.parent.iterdir()) == ["husky-run.mcap"]


def write_husky_bag(path: Path) -> Path:
    """The mode on the robot's own topic and a status line: nothing FTT reads
    by its type (fixes, transforms, poses, maps, images)."""
    rec = Recording()
    for k in range(LAST):
        rec.mode("bool", "/husky/robot_mode", k + 0.5, mode_at(k))
        rec.add(
            "/husky/status", "std_msgs/msg/String", k, rec.new("std_msgs/msg/String", data="ok")
        )
    return rec.write(path, "sqlite3")


def test_an_import_that_stores_nothing_leaves_nothing_and_the_robots_file_fixes_it(
    vehicle, media_root, tmp_path
):
    bag = write_husky_bag(tmp_path / "run")
    with pytest.raises(CommandError) as refused:
        run_command(bag, "--vehicle", "husky")
    said = str(refused.value)
    assert said.startswith("Nothing of run was stored")
    assert "/husky/robot_mode (std_msgs/msg/Bool), /husky/status (std_msgs/msg/String)" in said
    assert "the mode topic read (robot_mode)" in said  # the default it looked at
    assert row_counts()["TestEvent"] == 0  # no closed, empty event holding the bag's uids
    # The robot's own parameters file, as ftt_collect saves it, plus one of ROS's own.
    robot = tmp_path / "husky.yaml"
    write_file(robot, {"topics.robot_mode": "/husky/robot_mode"})
    robot.write_text(
        robot.read_text().replace("ros__parameters:", "ros__parameters:\n    use_sim_time: false")
    )
    err = io.StringIO()
    out = io.StringIO()
    call_command(
        "ftt_import_bag",
        str(bag),
        "--vehicle",
        "husky",
        "--params-file",
        str(robot),
        stdout=out,
        stderr=err,
    )
    assert "3 master segments" in out.getvalue()
    assert "added 0 Pose, 0 LocalPose" in out.getvalue()
    assert "Not collector parameters, ignored: use_sim_time" in err.getvalue()
    assert [(m.segment_type_id, m.start) for m in masters()] == [
        ("auto", at(0.5)),
        ("ito", at(20.5)),
        ("auto", at(40.5)),
    ]


def test_an_unreadable_parameters_file_is_named(vehicle, media_root, tmp_path):
    bag = write_husky_bag(tmp_path / "run")
    other = tmp_path / "other.yaml"
    other.write_text("some_other_node:\n  ros__parameters:\n    x: 1\n")
    with pytest.raises(CommandError, match="has no ros__parameters for ftt_collector"):
        run_command(bag, "--vehicle", "husky", "--params-file", other)
    with pytest.raises(CommandError, match="Cannot read parameters file"):
        run_command(bag, "--vehicle", "husky", "--params-file", tmp_path / "missing.yaml")
    assert row_counts()["TestEvent"] == 0
