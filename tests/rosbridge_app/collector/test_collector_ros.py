"""Publisher processes → ftt_collect process → rows, over real ROS 2 (loopback, own domain)."""

import io
import math
import time

import numpy as np
import pytest
import yaml
from django.core.exceptions import ValidationError
from PIL import Image as PilImage

from events.models import Segment, Vehicle
from events.services import logs
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.services.collectors import issue_command
from telemetry.models import Image as StoredImage
from telemetry.models import LocalPose, MapImage, Pose
from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]


def now_stamp(header):
    t = time.time()
    header.stamp.sec, header.stamp.nanosec = int(t), int((t % 1) * 1e9)


def latched():
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )


def masters(leg):
    return list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start"))


def test_every_input_type_ends_up_in_the_database(ros, start_collector, robot_leg):
    from geometry_msgs.msg import TransformStamped
    from nav_msgs.msg import OccupancyGrid
    from sensor_msgs.msg import CompressedImage, Image, NavSatFix
    from std_msgs.msg import Bool
    from tf2_msgs.msg import TFMessage

    # A latched map published before the collector exists must still arrive.
    grid = OccupancyGrid()
    grid.header.frame_id = "map"
    grid.info.width, grid.info.height, grid.info.resolution = 40, 20, 0.05
    grid.info.origin.position.x, grid.info.origin.position.y = -1.0, -0.5
    grid.info.origin.orientation.z, grid.info.origin.orientation.w = math.sin(0.2), math.cos(0.2)
    grid.data = [100] * 40 + [0] * 760
    map_publisher = ros.publisher(OccupancyGrid, "/map", latched())
    map_publisher.publish(grid)

    collector = start_collector(
        params={
            "params.image_buffer_size": 2,
            "params.image_buffer_step": 0.1,
            "topics.image_compressed": "image_compressed",
        }
    )
    mode = ros.publisher(Bool, "/robot_mode")
    fix = ros.publisher(NavSatFix, "/gps_fix")
    tf = ros.publisher(TFMessage, "/tf", 100)
    tf_static = ros.publisher(TFMessage, "/tf_static", latched())
    camera = ros.publisher(Image, "/image")
    compressed = ros.publisher(CompressedImage, "/image_compressed")
    for pub in (mode, fix, tf, camera, compressed):
        ros.wait_subscribed(pub)

    assert ros.trigger("/get_ftt_logging").success is False
    mode.publish(Bool(data=False))  # said once, before logging starts
    answer = ros.set_logging(True)
    assert answer.success, answer.message
    assert ros.trigger("/get_ftt_logging").success is True
    wait_for(lambda: len(masters(robot_leg)) == 1, what="the ITO master")

    def transform(parent, child, x, y, yaw):
        t = TransformStamped()
        now_stamp(t.header)
        t.header.frame_id, t.child_frame_id = parent, child
        t.transform.translation.x, t.transform.translation.y = x, y
        t.transform.rotation.z, t.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        return t

    tf_static.publish(TFMessage(transforms=[transform("map", "odom", 10.0, 0.0, 0.0)]))
    red = np.zeros((48, 64, 3), np.uint8)
    red[..., 0] = 230
    for i in range(12):
        f = NavSatFix()
        now_stamp(f.header)
        f.latitude, f.longitude = 50.6 + i * 1e-5, 7.1  # ~1.1 m apart
        f.status.status = 0
        fix.publish(f)
        tf.publish(TFMessage(transforms=[transform("odom", "base_link", i * 1.0, 0.0, 0.3)]))
        frame = Image(height=48, width=64, encoding="rgb8", step=64 * 3, data=red.tobytes())
        now_stamp(frame.header)
        camera.publish(frame)
        time.sleep(0.25)
    bad = NavSatFix(latitude=float("nan"), longitude=7.1)
    bad.status.status = 0
    fix.publish(bad)
    no_fix = NavSatFix(latitude=10.0, longitude=10.0)
    no_fix.status.status = -1
    fix.publish(no_fix)
    jpeg = io.BytesIO()
    PilImage.new("RGB", (32, 24), (0, 0, 230)).save(jpeg, format="JPEG")
    compressed.publish(CompressedImage(format="jpeg", data=jpeg.getvalue()))
    time.sleep(0.3)
    mode.publish(Bool(data=True))
    wait_for(lambda: len(masters(robot_leg)) == 2, what="the AUTO master")
    answer = ros.set_logging(False)
    assert answer.success, answer.message
    wait_for(lambda: masters(robot_leg)[-1].end is not None, what="stop closing the master")

    ito, auto = masters(robot_leg)
    assert (ito.segment_type_id, auto.segment_type_id) == ("ito", "auto")
    assert list(ito.children.values_list("ito_reason_id", flat=True)) == ["unassigned"]
    assert auto.start_position is not None and auto.start_local_x == pytest.approx(21.0)
    poses = Pose.objects.filter(segment=ito)
    assert 8 <= poses.count() <= 13
    assert all(p.point.y >= 50 for p in Pose.objects.all())  # NaN and NO_FIX dropped
    local = list(LocalPose.objects.filter(segment=ito).order_by("robot_stamp"))
    assert len(local) >= 8 and local[-1].x == pytest.approx(21.0)
    assert all(p.yaw == pytest.approx(0.3) and p.frame == "map" for p in local)
    stored_map = MapImage.objects.get(shift=robot_leg.shift)
    assert (stored_map.width, stored_map.height) == (40, 20)
    assert stored_map.origin_yaw == pytest.approx(0.4)
    assert stored_map.origin_x == -1.0
    images = list(StoredImage.objects.filter(segment=auto).order_by("id"))
    assert len(images) == 2 and not StoredImage.objects.filter(segment=ito).exists()
    colours = [PilImage.open(img.image.path).convert("RGB").getpixel((5, 5)) for img in images]
    assert colours[0][0] > 180 and colours[0][2] < 60  # the rgb8 frame stays red
    assert colours[1][2] > 180 and colours[1][0] < 60  # the JPEG stays blue

    status = wait_for(
        lambda: Collector.objects.filter(name="collector", inputs__gps_fix__count__gte=14).first(),
        5,
        what="the heartbeat",
    )
    assert status.inputs["map"]["count"] == 1
    assert any(t["name"] == "/gps_fix" for t in status.topics)
    # A latched map published while the collector listens reaches both of its map
    # subscriptions; the status page must still count one map, not two. (Logging
    # is off by now, so this map is only counted, not stored.)
    grid.data = [0] * 760 + [100] * 40
    now_stamp(grid.header)
    map_publisher.publish(grid)
    status = wait_for(
        lambda: Collector.objects.filter(name="collector", inputs__map__count__gte=2).first(),
        5,
        what="the heartbeat counting map 2",
    )
    # A further heartbeat, which would carry a doubled count.
    status = wait_for(
        lambda: Collector.objects.filter(name="collector", last_seen__gt=status.last_seen).first(),
        5,
        what="the heartbeat after the one counting map 2",
    )
    assert status.inputs["map"]["count"] == 2
    assert collector.alive()


def test_parameters_services_and_gui_commands(ros, start_collector, robot_leg):
    from geometry_msgs.msg import PoseStamped
    from industrial_msgs.msg import RobotMode
    from rclpy.parameter import Parameter

    collector = start_collector()
    params = ros.parameters()
    assert params.wait_for_services(10)
    result = ros.await_future(
        params.set_parameters(
            [
                Parameter("params.robot_mode_type", value="industrial"),
                Parameter("params.use_tf", value=False),
            ]
        )
    )
    assert all(r.successful for r in result.results)
    refused = ros.await_future(
        params.set_parameters([Parameter("params.pose_min_distance", value=-1.0)])
    )
    assert not refused.results[0].successful
    assert ">= 0" in refused.results[0].reason
    saved = ros.trigger("/save_ftt_params")
    assert saved.success, saved.message
    on_disk = yaml.safe_load(collector.params_file.read_text())["ftt_collector"]["ros__parameters"]
    assert on_disk["params"]["robot_mode_type"] == "industrial"
    assert on_disk["params"]["use_tf"] is False

    # The GUI side: commands through the database. How fast they are answered is
    # measured by benchmarks/collector_throughput.py.
    record = Collector.objects.get(name="collector")
    command = issue_command(record, CollectorCommand.Kind.START_LOGGING, leg=robot_leg)
    command = wait_for(
        lambda: CollectorCommand.objects.filter(pk=command.pk, done__isnull=False).first(),
        5,
        0.05,
        "the start command",
    )
    assert command.success, command.message
    mode = ros.publisher(RobotMode, "/robot_mode")
    pose = ros.publisher(PoseStamped, "/local_pose")
    ros.wait_subscribed(mode)
    ros.wait_subscribed(pose)
    mode.publish(RobotMode(val=RobotMode.AUTO))
    wait_for(lambda: masters(robot_leg), what="the AUTO master")
    for i in range(5):
        p = PoseStamped()
        now_stamp(p.header)
        p.header.frame_id = "map"
        p.pose.position.x = float(i)
        p.pose.orientation.z, p.pose.orientation.w = math.sin(0.5), math.cos(0.5)
        pose.publish(p)
        time.sleep(0.15)
    wait_for(lambda: LocalPose.objects.count() >= 4, what="local poses from PoseStamped")
    assert LocalPose.objects.first().yaw == pytest.approx(1.0)

    # The operator ends the leg: logging stops first (the server orders it).
    logs.close_leg(robot_leg)
    wait_for(lambda: not Collector.objects.get(pk=record.pk).logging, 5, what="logging stopped")
    # The next leg is logged into once logging is started again.
    next_leg = logs.create_leg(shift=robot_leg.shift)
    issue_command(record, CollectorCommand.Kind.START_LOGGING, leg=next_leg)
    followed = wait_for(lambda: masters(next_leg), 10, what="the mode in the new leg")
    assert followed[0].segment_type_id == "auto"
    wait_for(lambda: Collector.objects.get(pk=record.pk).logging, 5, what="logging again")

    # A wrong value is refused before it reaches the robot.
    with pytest.raises(ValidationError, match="true or false"):
        issue_command(record, "set_parameters", {"parameters": {"params.use_tf": "yes"}})
    good = issue_command(
        record, "set_parameters", {"parameters": {"params.pose_min_distance": 2.0}}
    )
    stop = issue_command(Collector.objects.get(pk=record.pk), CollectorCommand.Kind.STOP_LOGGING)
    wait_for(
        lambda: not CollectorCommand.objects.filter(done__isnull=True).exists(),
        5,
        what="the commands",
    )
    good, stop = (CollectorCommand.objects.get(pk=c.pk) for c in (good, stop))
    assert good.success and good.result["parameters"]["params.pose_min_distance"] == 2.0
    assert stop.success
    wait_for(lambda: masters(next_leg)[0].end is not None, 5, what="the master closed")

    # Pointed at another vehicle while running, it logs into that vehicle's leg.
    other = Vehicle.objects.create(key="second-bot", short_description="Second robot")
    other_leg = logs.create_leg(
        shift=logs.create_shift(test_event=robot_leg.shift.test_event, vehicle=other)
    )
    result = ros.await_future(params.set_parameters([Parameter("vehicle", value="second-bot")]))
    assert result.results[0].successful
    # Started once the collector says which leg it now logs into, as the GUI shows.
    wait_for(
        lambda: Collector.objects.get(pk=record.pk).leg_id == other_leg.pk,
        10,
        what="the other vehicle's leg",
    )
    assert ros.set_logging(True).success
    mode.publish(RobotMode(val=RobotMode.MANUAL))
    wait_for(
        lambda: [m for m in masters(other_leg) if m.segment_type_id == "ito"],
        10,
        what="the take-over in the other vehicle's leg",
    )
    assert len(masters(next_leg)) == 1

    # Saving where the file cannot be written is reported as a failure.
    collector.params_file.unlink()
    collector.params_file.mkdir()
    failed = ros.trigger("/save_ftt_params")
    assert not failed.success and "Could not write" in failed.message
