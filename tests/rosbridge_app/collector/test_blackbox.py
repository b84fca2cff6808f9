"""The black-box buffer and its MCAP files, without a ROS graph."""

import os
import time
import uuid
from datetime import UTC, datetime

from rclpy.serialization import serialize_message

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.blackbox import Blackbox, snapshot_topics
from rosbridge_app.collector.mcap_files import MessageDefinitions, write_mcap
from rosbridge_app.collector.params import SPECS
from rosbridge_app.collector.ring_buffer import RingBuffer
from tests.support.mcap_files import read_mcap


def params(**changes):
    values = {name: spec.default for name, spec in SPECS.items()}
    values.update({f"snapshot.{k}": v for k, v in changes.items()})
    return values


def test_the_buffer_keeps_seconds_and_megabytes_and_counts_what_it_drops():
    buffer = RingBuffer(seconds=2.0, max_bytes=10_000)
    for i in range(30):  # one message every 0.1 s
        buffer.add(i * 100_000_000, "/a", b"x" * 100)
    assert [t for t, _, _ in buffer.items][0] == 900_000_000  # 2 s before the newest
    assert buffer.dropped == 0
    for i in range(30, 40):
        buffer.add(i * 100_000_000, "/big", b"y" * 3000)
    assert buffer.size <= 10_000
    assert buffer.dropped > 0
    assert buffer.items[-1][1] == "/big"


def test_a_file_has_the_messages_their_times_and_definitions_of_any_type(tmp_path):
    from industrial_msgs.msg import RobotMode
    from sensor_msgs.msg import NavSatFix

    messages = []
    for i in range(5):
        fix = NavSatFix(latitude=48.0 + i, longitude=11.0)
        messages.append((1_000 + i, "/gps_fix", serialize_message(fix)))
    messages.append((2_000, "/robot_mode", serialize_message(RobotMode(val=1))))
    types = {
        "/gps_fix": "sensor_msgs/msg/NavSatFix",
        "/robot_mode": "industrial_msgs/msg/RobotMode",
    }
    path = tmp_path / "s.mcap"
    topics = write_mcap(path, messages, types, MessageDefinitions())
    back = read_mcap(path)
    assert topics == {
        "/gps_fix": {"type": "sensor_msgs/msg/NavSatFix", "count": 5},
        "/robot_mode": {"type": "industrial_msgs/msg/RobotMode", "count": 1},
    }
    assert back["profile"] == "ros2"
    assert "MSG: sensor_msgs/NavSatStatus" in back["schemas"]["sensor_msgs/msg/NavSatFix"]
    assert "int8 MANUAL" in back["schemas"]["industrial_msgs/msg/RobotMode"]
    fixes = [(t, m.latitude) for topic, t, m in back["messages"] if topic == "/gps_fix"]
    assert fixes == [(1_000 + i, 48.0 + i) for i in range(5)]
    assert [m.val for topic, _, m in back["messages"] if topic == "/robot_mode"] == [1]


def test_default_topics_follow_the_collector_topics_and_need_a_publisher():
    graph = {
        "/robot_mode": ["std_msgs/msg/Bool"],
        "/tf": ["tf2_msgs/msg/TFMessage"],
        "/odom": ["nav_msgs/msg/Odometry"],
        "/other": ["std_msgs/msg/String"],
    }
    resolve = lambda name: name if name.startswith("/") else "/" + name  # noqa: E731
    assert snapshot_topics(params(), graph, resolve) == {
        "/robot_mode": "std_msgs/msg/Bool",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/odom": "nav_msgs/msg/Odometry",
    }
    chosen = snapshot_topics(params(topics="other, /tf"), graph, resolve)
    assert chosen == {"/other": "std_msgs/msg/String", "/tf": "tf2_msgs/msg/TFMessage"}


def test_default_topics_take_the_mode_sources_and_reason_topics():
    graph = {"/mavros/state": ["mavros_msgs/msg/State"], "/estop": ["std_msgs/msg/Bool"]}
    values = params()
    values["params.mode_sources"] = (
        "sources: [{topic: /mavros/state, type: mavros_msgs/msg/State, field: mode,"
        " auto: [OFFBOARD]}]"
    )
    values["params.reason_rules"] = (
        "rules: [{topic: /estop, type: std_msgs/msg/Bool, field: data, values: [true],"
        " reason: safety}]"
    )
    assert snapshot_topics(values, graph, lambda name: name) == {
        "/mavros/state": "mavros_msgs/msg/State",
        "/estop": "std_msgs/msg/Bool",
    }


def test_the_oldest_pending_snapshot_makes_room_and_a_too_big_one_is_dropped(tmp_path, caplog):
    from sensor_msgs.msg import CompressedImage

    sent = []
    box = Blackbox(sent.append, params(before=5.0, after=0.0, disk_budget_mb=1))
    box.directory = tmp_path
    box.types["/s"] = "sensor_msgs/msg/CompressedImage"
    # Random bytes: the file's compression cannot make them smaller.
    payload = serialize_message(CompressedImage(format="jpeg", data=os.urandom(400_000)))
    for _ in range(3):
        box.receive("/s", payload)
        box.trigger(datetime.now(UTC), str(uuid.uuid4()), "test")
        time.sleep(0.01)
        box.poll()
        box._pool.submit(lambda: None).result()  # the writer has finished
        box.buffer.items.clear()
        box.buffer.size = 0
    files = sorted(tmp_path.glob("snapshot-*.mcap"))
    assert len(sent) == 3 and all(e.kind == ev.RECORDING for e in sent)
    assert len(files) == 2  # 3 × 0.4 MB do not fit 1 MB: the first one went
    assert [str(f) for f in files] == sorted(e.data["path"] for e in sent[1:])
    assert "disk budget for snapshots full" in caplog.text
    for _ in range(3):
        box.receive("/s", payload)
    box.trigger(datetime.now(UTC), None, "test")
    box.close()
    assert len(sent) == 3
    assert "more than the disk budget" in caplog.text


def test_nothing_is_collected_when_snapshots_are_off():
    box = Blackbox(lambda e: None, params(enabled=False))
    assert box.trigger(datetime.now(UTC), None, "test") is None
    assert box.pending == []


def test_a_flood_of_large_messages_stays_within_the_memory_bound(tmp_path, caplog):
    from std_msgs.msg import UInt8MultiArray

    sent = []
    box = Blackbox(sent.append, params(buffer_mb=1, after=0.0))
    box.directory = tmp_path
    box.types["/flood"] = "std_msgs/msg/UInt8MultiArray"
    frames = [bytes([i]) * 100_000 for i in range(50)]
    for frame in frames:
        box.receive("/flood", serialize_message(UInt8MultiArray(data=frame)))
        assert box.buffer.size <= 1024 * 1024
    box.poll()
    assert "snapshot buffer full" in caplog.text
    box.trigger(datetime.now(UTC), None, "test")
    box.close()
    (event,) = sent
    kept = [m.data[0] for _, _, m in read_mcap(event.data["path"])["messages"]]
    assert kept == list(range(50 - len(kept), 50)) and 5 <= len(kept) <= 10  # the newest
    assert box.buffer.dropped == 50 - len(kept)
