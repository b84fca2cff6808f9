"""MCAP files (ROS 2 profile, CDR messages, ``ros2msg`` schemas) from raw messages,
and the message definitions their schemas hold."""

import os
import sys
from pathlib import Path

from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype


class MessageDefinitions:
    """``ros2msg`` schema text for any message type: from rosbags' ROS 2 store,
    or from the ``share/<pkg>/msg/<Type>.msg`` files of installed interfaces
    (FTT's vendored ones and anything on AMENT_PREFIX_PATH)."""

    def __init__(self, store=None):
        # A bag reader's type store describes the bag's data exactly; live, the
        # ROS 2 store is made at the first snapshot (it takes a second to build).
        self.store = store
        self.cache: dict[str, str] = {}

    def load(self) -> None:
        if self.store is None:
            self.store = get_typestore(Stores.ROS2_JAZZY)

    def text(self, typename: str) -> str:
        self.load()
        if typename not in self.cache:
            self._register(typename)
            self.cache[typename] = self.store.generate_msgdef(typename, ros_version=2)[0]
        return self.cache[typename]

    def _register(self, typename: str) -> None:
        if typename in self.store.fielddefs:
            return
        pkg, _, name = typename.split("/")
        for prefix in [*os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep), sys.prefix]:
            path = Path(prefix) / "share" / pkg / "msg" / f"{name}.msg"
            if prefix and path.is_file():
                types = get_types_from_msg(path.read_text(), typename)
                self.store.register(types)
                self._register_fields(types)
                return
        raise LookupError(f"no message definition for {typename}")

    def _register_fields(self, types: dict) -> None:
        for _, (_, fields) in types.items():
            for _, desc in fields:
                self._register_field(desc)

    def _register_field(self, desc) -> None:
        kind, detail = desc
        if kind == Nodetype.NAME:
            self._register(detail)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            self._register_field(detail[0])


def part_path(path: Path) -> Path:
    """Where ``path`` is written until it is complete (never a ``snapshot-*.mcap`` name)."""
    return path.with_name(f".{path.name}.part")


class McapFile:
    """An MCAP file being written from messages (t_ns, topic, bytes), in as many
    pieces as wanted; it gets its name only when :meth:`finish` has completed it."""

    def __init__(self, path: Path, types: dict[str, str], definitions):
        self.path, self.types, self.definitions = path, types, definitions
        self.counts: dict[str, int] = {}
        self.schemas: dict[str, int] = {}
        self.channels: dict[str, int] = {}
        self.file = open(part_path(path), "wb")  # noqa: SIM115 - closed by finish/abandon
        self.writer = Writer(self.file, compression=CompressionType.LZ4)
        self.writer.start(profile="ros2", library="ftt_collect")

    def add(self, messages: list) -> None:
        writer, counts, channels = self.writer, self.counts, self.channels
        for t_ns, topic, data in messages:
            channel = channels.get(topic)
            if channel is None:
                channel = channels[topic] = self._channel(topic)
            counts[topic] = counts.get(topic, 0) + 1
            writer.add_message(
                channel, log_time=t_ns, data=data, publish_time=t_ns, sequence=counts[topic]
            )

    def _channel(self, topic: str) -> int:
        typename = self.types[topic]
        if typename not in self.schemas:
            self.schemas[typename] = self.writer.register_schema(
                name=typename, encoding="ros2msg", data=self.definitions.text(typename).encode()
            )
        return self.writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=self.schemas[typename]
        )

    def finish(self) -> dict:
        """Complete and name the file; {topic: {type, count}}."""
        with self.file:
            self.writer.finish()
        os.replace(part_path(self.path), self.path)
        counts = sorted(self.counts.items())
        return {topic: {"type": self.types[topic], "count": n} for topic, n in counts}

    def abandon(self) -> None:
        self.file.close()
        part_path(self.path).unlink(missing_ok=True)


def write_mcap(path: Path, messages: list, types: dict[str, str], definitions) -> dict:
    """Write messages (t_ns, topic, bytes) to an MCAP file; {topic: {type, count}}."""
    mcap = McapFile(path, types, definitions)
    try:
        mcap.add(messages)
        return mcap.finish()
    except BaseException:
        mcap.abandon()
        raise
