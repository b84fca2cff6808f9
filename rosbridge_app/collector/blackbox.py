"""Black-box snapshots: the last seconds of raw robot messages, as MCAP files.

The node hands every message of the snapshot topics to :meth:`Blackbox.receive`
still serialized (raw subscriptions), so the hot path is one deque append.
At a switch to ITO, or on request, the messages from ``before`` seconds before
until ``after`` seconds after are collected and written to an MCAP file (ROS 2
profile, CDR messages, ``ros2msg`` schemas) in the pending directory; then a
``recording`` event goes through the outbox like everything else.  The
recorder moves the file to media storage and deletes it only after the row is
committed, so an outage or a restart loses nothing.

The windows are collected in the ROS executor thread.  Building the file
(records, chunks, compression, CRCs: 0.1 s of CPU for a 20 s window, 0.3 s
with the message definitions at the first one) is Python work: in a thread of
the collector it held the interpreter lock that the executor and the database
writer need, for up to seconds on a loaded machine.  So a child process
(:class:`WriterProcess`) builds the files, and the collector's writer thread
only hands it the messages (bytes that are already there) and waits.
"""

import importlib
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
import uuid
from collections import deque
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.events import Event

log = logging.getLogger("ftt.collector")

MB = 1024 * 1024
# Messages handed to the snapshot writer process at a time.
PIECE = 8 * MB
# Added to the snapshot topics when they are published (common names on most robots).
OPTIONAL_TOPICS = ("odom", "cmd_vel")
DEFAULT_TOPIC_PARAMETERS = ("robot_mode", "gps_fix", "tf", "tf_static", "image_compressed")


def _ns(at: datetime) -> int:
    return int(at.timestamp() * 1e9)


def _at(ns: int) -> datetime:
    return datetime.fromtimestamp(ns / 1e9, UTC)


class RingBuffer:
    """(receive time ns, topic, bytes), bounded by age and by total size; the
    oldest go first and ``dropped`` counts the messages dropped for size."""

    def __init__(self, seconds: float, max_bytes: int):
        self.seconds, self.max_bytes = seconds, max_bytes
        self.items: deque = deque()
        self.size = 0
        self.dropped = 0

    def add(self, t_ns: int, topic: str, data: bytes) -> None:
        self.items.append((t_ns, topic, data))
        self.size += len(data)
        oldest = t_ns - int(self.seconds * 1e9)
        items = self.items
        while items and (items[0][0] < oldest or self.size > self.max_bytes):
            if items[0][0] >= oldest:
                self.dropped += 1
            self.size -= len(items.popleft()[2])

    def since(self, t_ns: int) -> list:
        return [item for item in self.items if item[0] >= t_ns]


@dataclass
class Snapshot:
    """A window being collected: what was buffered at the trigger plus what
    arrives until ``end``."""

    uid: uuid.UUID
    master: str | None
    reason: str
    start: int
    end: int
    messages: list = field(default_factory=list)
    size: int = 0


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


# --- the writer process ---------------------------------------------------------------

# The writer process's definitions: it keeps them from one snapshot to the next.
_definitions = MessageDefinitions()


def _start_writer(collector: int) -> None:
    """Runs first in the writer process.  Ctrl-C and SIGTERM reach the whole
    process group: the collector decides when its writer ends (it writes the
    open windows at exit)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    threading.Thread(target=_end_with, args=(collector,), daemon=True).start()
    _definitions.load()  # at the trigger, not when the window has passed


def _end_with(collector: int) -> None:
    """A killed collector closes no pipe the writer would notice (the writer
    holds both ends of its work queue): it would wait for work for ever."""
    while os.getppid() == collector:
        time.sleep(1.0)
    os._exit(0)


# The file the writer process is writing: the window comes in pieces, so that
# neither process holds a second copy of a whole large window.
_file: McapFile | None = None


def _begin(path: str, types: dict[str, str]) -> None:
    global _file
    if _file is not None:  # the collector gave up on it (it cannot happen otherwise)
        _file.abandon()
    _file = McapFile(Path(path), types, _definitions)


def _add(messages: list) -> None:
    _file.add(messages)


def _finish() -> dict:
    global _file
    mcap, _file = _file, None
    return mcap.finish()


def pieces(messages: list, size: int) -> list[list]:
    """Consecutive slices of messages (t_ns, topic, bytes) of about ``size`` bytes."""
    out, start, total = [], 0, 0
    for i, message in enumerate(messages):
        total += len(message[2])
        if total >= size:
            out.append(messages[start : i + 1])
            start, total = i + 1, 0
    if start < len(messages):
        out.append(messages[start:])
    return out


class WriterDied(Exception):
    pass


class WriterProcess:
    """The child process that writes snapshot files, started by the first
    trigger and kept.  'spawn': the collector has DDS threads running, and a
    forked copy of them is undefined; a spawned interpreter imports this module
    and the mcap library only.  If it dies (killed, out of memory) the
    collector logs it and starts a new one for the next file."""

    def __init__(self):
        self._pool: ProcessPoolExecutor | None = None
        self._lock = threading.Lock()
        self.pid: int | None = None

    def start(self) -> ProcessPoolExecutor:
        with self._lock:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(
                    1,
                    mp_context=multiprocessing.get_context("spawn"),
                    initializer=_start_writer,
                    initargs=(os.getpid(),),
                )
                self._pool.submit(os.getpid).add_done_callback(self._started)
            return self._pool

    def _started(self, future: Future) -> None:
        if future.exception() is None:
            self.pid = future.result()
            log.info("snapshot writer process started (pid %d)", self.pid)

    def write(self, path: Path, messages: list, types: dict[str, str]) -> dict:
        """Write the file in the child; a child that dies gets one successor to try again."""
        for attempt in (1, 2):
            pool = self.start()
            try:
                pool.submit(_begin, str(path), types).result()
                for piece in pieces(messages, PIECE):
                    pool.submit(_add, piece).result()
                return pool.submit(_finish).result()
            except BrokenProcessPool:
                log.error(
                    "the snapshot writer process (pid %s) died before it finished %s; %s",
                    self.pid,
                    path.name,
                    "starting a new one to try again" if attempt == 1 else "snapshot lost",
                )
                part_path(path).unlink(missing_ok=True)
                with self._lock:
                    if self._pool is pool:
                        self._pool, self.pid = None, None
                pool.shutdown(wait=False)
        raise WriterDied(f"the snapshot writer died twice while writing {path.name}")

    def close(self) -> None:
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True)


class Blackbox:
    def __init__(self, sink, params: dict):
        self.sink = sink
        self.types: dict[str, str] = {}  # topic → message type of the subscriptions
        # Latched topics (static TF) are published once: their last message is
        # repeated at the start of every window, or a snapshot would lack them.
        self.latched: set[str] = set()
        self.last: dict[str, bytes] = {}
        self.pending: list[Snapshot] = []
        self.directory: Path | None = None
        self.written = 0
        self._dropped_said = (0, 0.0)  # count and time of the last warning
        # Waits for the writer process, one file after the other.
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="ftt-snapshot")
        self.writer = WriterProcess()
        self._lock = threading.Lock()  # the pending directory and its budget
        self.buffer = RingBuffer(0, 0)
        self.configure(params)

    def configure(self, params: dict) -> None:
        self.enabled = bool(params["snapshot.enabled"])
        self.before = float(params["snapshot.before"])
        self.after = float(params["snapshot.after"])
        self.budget = int(params["snapshot.disk_budget_mb"] * MB)
        self.buffer.seconds = self.before
        self.buffer.max_bytes = int(params["snapshot.buffer_mb"] * MB)

    def status(self) -> dict:
        return {
            "buffered_messages": len(self.buffer.items),
            "buffered_bytes": self.buffer.size,
            "dropped_for_size": self.buffer.dropped,
            "snapshots_written": self.written,
        }

    # --- executor thread ----------------------------------------------------------------

    def receive(self, topic: str, data: bytes, t_ns: int | None = None) -> None:
        """Keep one message; ``t_ns`` (receive time) is now unless given (benchmarks)."""
        t_ns = t_ns or time.time_ns()
        self.buffer.add(t_ns, topic, data)
        if topic in self.latched:
            self.last[topic] = data
        for snap in self.pending:
            if t_ns <= snap.end:
                snap.messages.append((t_ns, topic, data))
                snap.size += len(data)

    def trigger(self, at: datetime, master: str | None, reason: str) -> uuid.UUID | None:
        if not self.enabled:
            return None
        start, end = _ns(at) - int(self.before * 1e9), _ns(at) + int(self.after * 1e9)
        messages = self.buffer.since(start)
        present = {m[1] for m in messages}
        repeated = [(start, t, data) for t, data in self.last.items() if t not in present]
        snap = Snapshot(uuid.uuid4(), master, reason, start, end, repeated + messages)
        snap.size = sum(len(m[2]) for m in snap.messages)
        self.pending.append(snap)
        try:
            self.writer.start()  # ready when the window has passed
        except Exception:  # the write tries again; a trigger is called in ROS callbacks
            log.exception("could not start the snapshot writer process")
        return snap.uid

    def poll(self) -> None:
        """Hand finished windows to the writer thread (called a few times a second)."""
        now = time.time_ns()
        for snap in [s for s in self.pending if s.end < now]:
            self.pending.remove(snap)
            self._pool.submit(self._write, snap, dict(self.types))
        said, said_at = self._dropped_said
        if self.buffer.dropped > said and time.monotonic() - said_at > 60:
            log.warning(
                "snapshot buffer full (snapshot.buffer_mb): %d oldest messages dropped so far",
                self.buffer.dropped,
            )
            self._dropped_said = (self.buffer.dropped, time.monotonic())

    def close(self, wait: bool = True) -> None:
        """Write what is pending with the messages it has, then stop the writer."""
        for snap in self.pending:
            snap.end = min(snap.end, time.time_ns())
            self._pool.submit(self._write, snap, dict(self.types))
        self.pending = []
        self._pool.shutdown(wait=wait)
        if wait:
            self.writer.close()

    # --- writer thread ------------------------------------------------------------------

    def _write(self, snap: Snapshot, types: dict[str, str]) -> None:
        try:
            self._write_file(snap, types)
        except WriterDied as exc:
            log.error("snapshot %s lost: %s", snap.uid, exc)
        except Exception:
            log.exception("could not write the snapshot %s", snap.uid)

    def _write_file(self, snap: Snapshot, types: dict[str, str]) -> None:
        if self.directory is None:
            return
        self.directory.mkdir(parents=True, exist_ok=True)
        # Left by a writer that died with its collector (this thread writes one at a time).
        for part in self.directory.glob(".snapshot-*.part"):
            part.unlink(missing_ok=True)
        messages = [m for m in snap.messages if m[1] in types]
        if not self._make_room(snap.size):
            log.warning(
                "snapshot %s dropped: %.1f MB is more than the disk budget",
                snap.uid,
                snap.size / MB,
            )
            return
        stamp = _at(snap.start).strftime("%Y%m%d-%H%M%S")
        path = self.directory / f"snapshot-{stamp}-{snap.uid.hex[:8]}.mcap"
        topics = self.writer.write(path, messages, types)
        self.written += 1
        data = {
            "master": snap.master,
            "reason": snap.reason,
            "path": str(path),
            "start": _at(snap.start).isoformat(),
            "end": _at(snap.end).isoformat(),
            "topics": topics,
        }
        self.sink(Event(ev.RECORDING, _at(snap.end), data, uid=snap.uid))
        log.info("snapshot %s: %d messages on %d topics", path.name, len(messages), len(topics))

    def _make_room(self, size: int) -> bool:
        """Drop the oldest pending files until ``size`` more bytes fit the budget."""
        if size > self.budget:
            return False
        with self._lock:
            files = sorted(self.directory.glob("snapshot-*.mcap"), key=lambda p: p.stat().st_mtime)
            used = sum(p.stat().st_size for p in files)
            while files and used + size > self.budget:
                oldest = files.pop(0)
                used -= oldest.stat().st_size
                oldest.unlink(missing_ok=True)
                log.warning("disk budget for snapshots full: dropped the pending %s", oldest.name)
        return True


def snapshot_topics(params: dict, graph: dict[str, list[str]], resolve) -> dict[str, str]:
    """{resolved topic: message type} of the snapshot topics published now."""
    names = [t.strip() for t in params["snapshot.topics"].split(",") if t.strip()]
    if not names:
        names = [params[f"topics.{key}"] for key in DEFAULT_TOPIC_PARAMETERS]
        names += OPTIONAL_TOPICS
    wanted = {}
    for name in names:
        if not name:
            continue
        topic = resolve(name)
        types = graph.get(topic)
        if types:
            wanted[topic] = types[0]
    return wanted


def message_class(typename: str):
    """The rclpy message class of 'pkg/msg/Type' (needed even for a raw subscription)."""
    pkg, kind, name = typename.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
