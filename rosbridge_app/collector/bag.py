"""Robot recordings (ROS 1 .bag, ROS 2 sqlite3/mcap) → the collector's events.

For the bag player and for bag imports.  Reading needs only rosbags (no ROS);
:func:`to_rclpy` (the player) needs rclpy.

* :func:`bag_messages` yields every message with its record time;
* :func:`feed_pipeline` routes them into a :class:`Pipeline` exactly as the
  live node's subscriptions do;
* :func:`bag_events` returns the events a live collector would have produced
  had it been logging while the bag was recorded; store them with
  :func:`rosbridge_app.collector.event_writer.write_events`.
"""

import array
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import yaml
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from rosbridge_app.collector.events import Event
from rosbridge_app.collector.message_fields import message_class
from rosbridge_app.collector.modes import BOOL, INDUSTRIAL, mode_of
from rosbridge_app.collector.params import SPECS
from rosbridge_app.collector.pipeline import Pipeline

ROBOT_MODE = "industrial_msgs/msg/RobotMode"
BOOL_TYPE = "std_msgs/msg/Bool"
NAVSATFIX = "sensor_msgs/msg/NavSatFix"
TF = "tf2_msgs/msg/TFMessage"
POSE = "geometry_msgs/msg/PoseStamped"
GRID = "nav_msgs/msg/OccupancyGrid"
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
PROGRESS_EVERY = 2000  # routed messages between two progress reports
METADATA = "metadata.yaml"  # a ROS 2 bag directory's index of its files


@dataclass
class BagMessage:
    topic: str
    msgtype: str
    time_ns: int
    msg: object
    latched: bool

    @property
    def at(self) -> datetime:
        return datetime.fromtimestamp(self.time_ns / 1e9, tz=UTC)


@contextmanager
def open_bag(path: Path) -> Iterator[AnyReader]:
    """An open rosbags reader for a ROS 1 bag file, a ROS 2 bag directory or one
    of its files, or a bare .mcap file (a black-box snapshot, a file from
    Foxglove or ``mcap`` tools) with no metadata.yaml beside it."""
    path = Path(path)
    typestore = get_typestore(Stores.ROS2_JAZZY)
    if path.is_file() and path.suffix == ".mcap" and not (path.parent / METADATA).exists():
        # rosbags opens a ROS 2 bag only by its directory's metadata.yaml, so the
        # file gets a folder of its own with the metadata its summary gives.
        with tempfile.TemporaryDirectory(prefix="ftt-mcap-") as folder:
            (Path(folder) / path.name).symlink_to(path.resolve())
            (Path(folder) / METADATA).write_text(_rosbag2_metadata(path))
            with AnyReader([Path(folder)], default_typestore=typestore) as reader:
                yield reader
        return
    if path.is_file() and path.suffix in (".db3", ".mcap"):
        path = path.parent  # rosbag2 is opened by its directory (metadata.yaml)
    with AnyReader([path], default_typestore=typestore) as reader:
        yield reader


def _rosbag2_metadata(path: Path) -> str:
    """metadata.yaml (rosbag2 version 8) for one MCAP file, from its summary."""
    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    if summary is None or summary.statistics is None:
        # A file cut short; the mcap CLI's "mcap recover" writes a whole one.
        raise ValueError(f"{path.name} has no summary (cut short?); try 'mcap recover'")
    channels, schemas = summary.channels, summary.schemas
    counts = summary.statistics.channel_message_counts
    first = summary.statistics.message_start_time
    last = summary.statistics.message_end_time
    topics = [
        {
            "topic_metadata": {
                "name": channel.topic,
                "type": schemas[channel.schema_id].name if channel.schema_id in schemas else "",
                "serialization_format": channel.message_encoding,
                "offered_qos_profiles": channel.metadata.get("offered_qos_profiles", ""),
            },
            "message_count": counts.get(channel.id, 0),
        }
        for channel in channels.values()
    ]
    total = sum(counts.values())
    return yaml.safe_dump(
        {
            "rosbag2_bagfile_information": {
                "version": 8,
                "storage_identifier": "mcap",
                "relative_file_paths": [path.name],
                "starting_time": {"nanoseconds_since_epoch": first},
                "duration": {"nanoseconds": last - first},
                "message_count": total,
                "topics_with_message_count": topics,
                "compression_format": "",
                "compression_mode": "",
            }
        }
    )


def latched(connection) -> bool:
    ext = connection.ext
    if getattr(ext, "latching", None):
        return True
    for qos in getattr(ext, "offered_qos_profiles", None) or []:
        if "transient_local" in str(getattr(qos, "durability", "")).lower():
            return True
    return connection.topic in ("/tf_static", "tf_static")


def bag_messages(path: Path, topics: set[str] | None = None) -> Iterator[BagMessage]:
    with open_bag(path) as reader:
        connections = [c for c in reader.connections if topics is None or c.topic in topics]
        if not connections:
            return  # rosbags reads an empty list as every connection
        latched_ids = {c.id: latched(c) for c in connections}
        for connection, time_ns, raw in reader.messages(connections=connections):
            yield BagMessage(
                connection.topic,
                connection.msgtype,
                time_ns,
                reader.deserialize(raw, connection.msgtype),
                latched_ids[connection.id],
            )


def _same_topic(a: str, b: str) -> bool:
    return bool(a) and bool(b) and a.lstrip("/") == b.lstrip("/")


def route(pipeline: Pipeline, topic: str, msgtype: str):
    """The pipeline method for a bag topic, chosen by the configured topic
    names first and by message type otherwise; None: not something we record."""
    p = pipeline.params
    if pipeline.mode_sources is not None:
        # The same mode sources as live; the classic mode topic is not read then.
        config = pipeline.mode_sources.config
        for source_topic, indices in config.by_topic().items():
            if _same_topic(topic, source_topic) and msgtype == config.sources[indices[0]].type:
                return lambda m, at, indices=indices: pipeline.on_mode_source(indices, m, at)
        if msgtype == ROBOT_MODE or _same_topic(topic, p["topics.robot_mode"]):
            return None
    if pipeline.reasons is not None:
        for rule_topic, rule_type in pipeline.reasons.topics().items():
            if _same_topic(topic, rule_topic) and msgtype == rule_type:
                return lambda m, at: pipeline.on_reason_signal(topic, m, at)
    if msgtype == ROBOT_MODE:
        return lambda m, at: _mode(pipeline, m, at, INDUSTRIAL)
    if msgtype == BOOL_TYPE and _same_topic(topic, p["topics.robot_mode"]):
        return lambda m, at: _mode(pipeline, m, at, BOOL)
    if msgtype == NAVSATFIX:
        return pipeline.on_fix
    if msgtype == TF:
        static = _same_topic(topic, p["topics.tf_static"]) or topic.endswith("tf_static")
        return lambda m, at: pipeline.on_tf(m, at, static=static)
    if msgtype == POSE:
        return pipeline.on_pose
    if msgtype == GRID:
        return pipeline.on_grid
    if msgtype == IMAGE:
        return pipeline.on_image
    if msgtype == COMPRESSED:
        if _same_topic(topic, p["topics.map_jpeg"]):
            return pipeline.on_map_jpeg
        return lambda m, at: pipeline.on_image(m, at, compressed=True)
    return None


def _mode(pipeline: Pipeline, msg, at, mode_type: str) -> None:
    mode = mode_of(msg, mode_type)
    if mode is not None:
        pipeline.on_mode_value(mode, at)


def feed_pipeline(
    path: Path, pipeline: Pipeline, progress: Callable[[int, int], None] | None = None
) -> dict[str, int]:
    """Route every message of the bag into the pipeline; returns counts per topic.

    ``progress(done, total)`` hears about the routed messages now and then."""
    with open_bag(path) as reader:
        handlers = {
            (c.topic, c.msgtype): route(pipeline, c.topic, c.msgtype) for c in reader.connections
        }
        total = sum(
            c.msgcount for c in reader.connections if handlers[(c.topic, c.msgtype)] is not None
        )
    # Topics we do not record (point clouds, say) are never deserialised.
    wanted = {topic for (topic, _), handler in handlers.items() if handler is not None}
    counts: dict[str, int] = {}
    last = None
    done = 0
    for m in bag_messages(path, wanted):
        handler = handlers.get((m.topic, m.msgtype))
        if handler is None:
            continue
        at = m.at
        handler(m.msg, at)
        counts[m.topic] = counts.get(m.topic, 0) + 1
        done += 1
        if progress is not None and done % PROGRESS_EVERY == 0:
            progress(done, total)
        if last is None or (at - last).total_seconds() >= 1.0:
            pipeline.tick(at)
            last = at
    if progress is not None:
        progress(total, total)
    return counts


def bag_events(
    path: Path,
    params: dict | None = None,
    *,
    stop_at_end: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> list[Event]:
    """The events of a whole bag, as a collector logging from the bag's first
    message would have produced them (the last segment closed at the end
    when ``stop_at_end``).  Pictures are still unrendered: Event.prepare()."""
    events: list[Event] = []
    pipeline = Pipeline(
        events.append, {**{k: s.default for k, s in SPECS.items()}, **(params or {})}
    )
    with open_bag(path) as reader:
        if not reader.message_count:
            return events
        first, last = (
            datetime.fromtimestamp(t / 1e9, tz=UTC) for t in (reader.start_time, reader.end_time)
        )
    pipeline.start_logging(first)
    feed_pipeline(path, pipeline, progress)
    if stop_at_end:
        pipeline.stop_logging(last)
    return events


# --- to live ROS messages (the player) ------------------------------------------------------


def rclpy_type(msgtype: str):
    package, _, name = msgtype.split("/")
    return message_class(f"{package}/msg/{name}")


def to_rclpy(value, cls):
    """Copy a rosbags message into a new rclpy message of class ``cls``,
    field by field (ROS 1 fields such as Header.seq are dropped)."""
    out = cls()
    for field, type_name in cls.get_fields_and_field_types().items():
        if not hasattr(value, field):
            continue
        setattr(out, field, _convert(getattr(value, field), getattr(out, field), type_name))
    return out


def _convert(value, current, type_name: str):
    if hasattr(current, "get_fields_and_field_types"):
        return to_rclpy(value, type(current))
    if type_name.startswith("sequence<") and "/" in type_name:
        inner = type_name[len("sequence<") :].split(",")[0].rstrip(">")
        package, name = inner.split("/")
        return [to_rclpy(v, message_class(f"{package}/msg/{name}")) for v in value]
    if isinstance(current, array.array):
        data = np.asarray(value)
        return array.array(current.typecode, data.astype(np.dtype(current.typecode)).tobytes())
    if isinstance(current, np.ndarray):
        return np.asarray(value, dtype=current.dtype)
    if isinstance(current, bytes) and isinstance(value, np.ndarray):
        return value.astype(np.uint8).tobytes()
    if isinstance(current, list) and isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value
