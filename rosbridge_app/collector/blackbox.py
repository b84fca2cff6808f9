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
only hands it the messages and waits, for a bounded time
(``snapshot.write_timeout``): a writer that is alive but stuck is killed and
replaced like one that died.

The hand-over must not take the collector's time either.  Pickled through a
pipe, 12 MB went 64 kB at a time: some 200 wake-ups of the writer thread, each
taking the interpreter lock back from the database writer while it stored a
mode switch.  Now the bytes of up to :data:`PIECE` go into an anonymous
memory file in one ``writev`` (the lock released) and the child gets the file
descriptor and an index of (time, topic, length): a few wake-ups per window.
The child runs SCHED_IDLE: it gets a core only when no thread of the collector,
the database or the robot wants it (and a waking thread takes it at once).
"""

import atexit
import importlib
import logging
import multiprocessing
import os
import signal
import sys
import tempfile
import threading
import time
import traceback
import uuid
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from datetime import UTC, datetime
from multiprocessing import reduction
from pathlib import Path

from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.base import Nodetype

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.events import Event

log = logging.getLogger("ftt.collector")

MB = 1024 * 1024
# Bytes handed to the snapshot writer process at a time (one memory file each):
# a 20 s window of the benchmark robot is one piece, and a 200 MB window never
# lies in memory twice.
PIECE = 32 * MB
# Added to snapshot.write_timeout per MB of the window.
WRITE_SECONDS_PER_MB = 1.0
# A new writer process must be ready (interpreter, mcap, type store) within this;
# a few seconds on a loaded machine.
START_TIMEOUT = 120.0
WRITER_NICE = 10  # where SCHED_IDLE is not to be had
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


def _serve(conn) -> None:
    """The writer process: files from requests on ``conn`` until the collector
    closes it or is gone (end of file either way).  Ctrl-C and SIGTERM reach the
    whole process group: the collector decides when its writer ends (it writes
    the open windows at exit).  SCHED_IDLE (niced where not available): on a
    busy machine the collector's own threads come first, a file may well be
    written a second later."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    _step_aside()
    _definitions.load()  # at the trigger, not when the window has passed
    conn.send(("ready", None))
    mcap, failed = None, None
    while True:
        try:
            op, arg = conn.recv()
            window = reduction.recv_handle(conn) if op == "add" else None
        except EOFError:
            return
        try:
            if op == "begin":
                if mcap is not None:  # the collector gave up on it
                    mcap.abandon()
                failed, mcap = None, None
                mcap = McapFile(Path(arg[0]), arg[1], _definitions)
            elif op == "add":
                try:
                    if failed is None:
                        mcap.add(read_window(window, arg))
                finally:
                    os.close(window)
                    conn.send(("added", None))
            elif op == "finish":
                if failed is not None:
                    conn.send(("error", failed))
                else:
                    conn.send(("done", mcap.finish()))
                mcap = None
        except Exception:
            failed = traceback.format_exc()
            if mcap is not None:
                mcap.abandon()
                mcap = None


def _step_aside() -> None:
    """Run only on a core that nothing else wants (SCHED_IDLE), where Linux
    has it; niced otherwise."""
    try:
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    except (AttributeError, OSError):
        os.nice(WRITER_NICE)


def window_file(messages: list) -> tuple[int, list]:
    """(descriptor of a memory file holding the messages' bytes one after the
    other, index [(t_ns, topic, length)]).  ``writev`` copies them in a few
    system calls, which release the interpreter lock."""
    if hasattr(os, "memfd_create"):
        fd = os.memfd_create("ftt-snapshot-window", os.MFD_CLOEXEC)
    else:
        fd = os.dup((f := tempfile.TemporaryFile()).fileno())
        f.close()
    try:
        datas = [m[2] for m in messages]
        step = os.sysconf("SC_IOV_MAX")
        for i in range(0, len(datas), step):
            chunk = datas[i : i + step]
            written = os.writev(fd, chunk)
            if written < sum(map(len, chunk)):  # a short write (rare): the rest
                rest = memoryview(b"".join(chunk))[written:]
                while rest:
                    rest = rest[os.write(fd, rest) :]
        return fd, [(t, topic, len(data)) for t, topic, data in messages]
    except BaseException:
        os.close(fd)
        raise


def read_window(fd: int, index: list) -> list:
    """The messages (t_ns, topic, bytes) of a :func:`window_file`."""
    out, offset = [], 0
    for t, topic, length in index:
        out.append((t, topic, os.pread(fd, length, offset)))
        offset += length
    return out


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


class SnapshotError(Exception):
    """The writer process could not write a file (and is still there)."""


class _Child:
    """One writer process and the collector's end of its pipe."""

    def __init__(self):
        context = multiprocessing.get_context("spawn")
        self.conn, theirs = context.Pipe()
        self.process = context.Process(
            target=_serve, args=(theirs,), name="ftt-snapshot-writer", daemon=False
        )
        self.process.start()
        theirs.close()  # so that its death is an end of file here
        self.pid = self.process.pid
        self.ready = False
        self.stuck = ""  # why the watchdog killed it

    def kill(self) -> None:
        self.process.kill()

    def close(self, wait: float) -> None:
        self.conn.close()  # its end of file: it returns
        self.process.join(wait)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(5)


class WriterProcess:
    """The child process that writes snapshot files, started by the first
    trigger and kept.  'spawn': the collector has DDS threads running, and a
    forked copy of them is undefined; a spawned interpreter imports this module
    and the mcap library only.  If it dies (killed, out of memory) or is stuck
    (alive but not done within its time), the collector logs it, kills it and
    starts a new one for the next file."""

    def __init__(self):
        self._child: _Child | None = None
        self._lock = threading.Lock()

    @property
    def pid(self) -> int | None:
        child = self._child
        return child.pid if child is not None else None

    def start(self) -> _Child:
        """The running writer, started if needed (without waiting for it to be ready)."""
        with self._lock:
            old = self._child
            if old is not None and not old.process.is_alive():
                log.error("the snapshot writer process (pid %d) died; starting a new one", old.pid)
                old.close(wait=0)
                self._child = None
            if self._child is None:
                self._child = _Child()
                log.info("snapshot writer process started (pid %d)", self._child.pid)
                # multiprocessing joins its children at exit: a writer whose pipe
                # is still open would keep the collector from ever exiting.
                atexit.unregister(self.close)
                atexit.register(self.close)
            return self._child

    def write(self, path: Path, messages: list, types: dict[str, str], timeout: float) -> dict:
        """Write the file in the child, which must be done within ``timeout``
        seconds once it runs; a child that dies or is stuck gets one successor
        to try again."""
        for attempt in (1, 2):
            child = self.start()
            try:
                return self._write(child, path, messages, types, timeout)
            except (OSError, EOFError):
                what = f"was stuck ({child.stuck}) and was killed" if child.stuck else "died"
                log.error(
                    "the snapshot writer process (pid %s) %s before it finished %s; %s",
                    child.pid,
                    what,
                    path.name,
                    "starting a new one to try again" if attempt == 1 else "snapshot lost",
                )
                child.kill()
                # Half a file, or a whole one it had no time to report: the
                # successor writes it again, or nothing is delivered.
                part_path(path).unlink(missing_ok=True)
                path.unlink(missing_ok=True)
                with self._lock:
                    if self._child is child:
                        self._child = None
                child.close(wait=5)
        raise WriterDied(f"the snapshot writer failed twice while writing {path.name}")

    def _write(self, child: _Child, path: Path, messages, types, timeout: float) -> dict:
        conn = child.conn
        if not child.ready:
            # Starting an interpreter and loading the type store: seconds on a
            # loaded machine, not part of the file's time.
            self._within(child, START_TIMEOUT, "not ready", conn.recv)
            child.ready = True
        work = lambda: self._exchange(conn, child.pid, path, messages, types)  # noqa: E731
        return self._within(child, timeout, "not done", work)

    @staticmethod
    def _exchange(conn, child_pid: int, path: Path, messages, types) -> dict:
        conn.send(("begin", (str(path), types)))
        for piece in pieces(messages, PIECE):
            fd, index = window_file(piece)
            try:
                conn.send(("add", index))
                reduction.send_handle(conn, fd, child_pid)
            finally:
                os.close(fd)
            conn.recv()  # taken: the next piece (so at most one is in memory twice)
        conn.send(("finish", None))
        status, result = conn.recv()
        if status == "error":
            raise SnapshotError(f"the writer process could not write {path.name}:\n{result}")
        return result

    @staticmethod
    def _within(child: _Child, seconds: float, what: str, work):
        """Run ``work``; a child not done by then is killed, which ends whatever
        ``work`` waits for (a full pipe, a reply) with an OSError or EOFError."""

        def stuck() -> None:
            child.stuck = f"{what} after {seconds:.0f} s"
            child.kill()

        watchdog = threading.Timer(seconds, stuck)
        watchdog.daemon = True
        watchdog.start()
        try:
            return work()
        finally:
            watchdog.cancel()

    def close(self) -> None:
        atexit.unregister(self.close)
        with self._lock:
            child, self._child = self._child, None
        if child is not None:
            child.close(wait=30)


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
        self.write_timeout = float(params["snapshot.write_timeout"])
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
        timeout = self.write_timeout + WRITE_SECONDS_PER_MB * snap.size / MB
        topics = self.writer.write(path, messages, types, timeout)
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
