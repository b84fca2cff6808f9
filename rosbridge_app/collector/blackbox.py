"""Black-box snapshots: the last seconds of raw robot messages, as MCAP files.

The node hands every message of the snapshot topics to :meth:`Blackbox.receive`
still serialized (raw subscriptions), so the hot path is one deque append.
At a switch to ITO, or on request, the messages from ``before`` seconds before
until ``after`` seconds after are collected; the writer process
(:mod:`~rosbridge_app.collector.snapshot_writer`) writes them to an MCAP file
in the pending directory, then a ``recording`` event goes through the spool
like everything else.  The event writer moves the file to media storage and
deletes it only after the row is committed, so an outage or a restart loses
nothing.
"""

import logging
import threading
import time
import uuid
from concurrent import futures
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from django.utils.translation import gettext

from rosbridge_app.collector import events as ev
from rosbridge_app.collector import mode_sources, reason_rules
from rosbridge_app.collector.disk_guard import TIGHT
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.ring_buffer import RingBuffer
from rosbridge_app.collector.snapshot_writer import MB, WriterDied, WriterProcess

log = logging.getLogger("ftt.collector")

# Added to snapshot.write_timeout per MB of the window.
WRITE_SECONDS_PER_MB = 1.0
# Added to the snapshot topics when they are published (common names on most robots).
OPTIONAL_TOPICS = ("odom", "cmd_vel")
DEFAULT_TOPIC_PARAMETERS = ("robot_mode", "gps_fix", "tf", "tf_static", "image_compressed")


def _ns(at: datetime) -> int:
    return int(at.timestamp() * 1e9)


def _at(ns: int) -> datetime:
    return datetime.fromtimestamp(ns / 1e9, UTC)


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
        self.guard = None  # the collector's DiskGuard: no snapshot on a (nearly) full disk
        self._futures: list = []
        self.written = 0
        self._dropped_warned = (0, 0.0)  # count and time of the last warning
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
            self._futures.append(self._pool.submit(self._write, snap, dict(self.types)))
        self._futures = [f for f in self._futures if not f.done()]
        warned, warned_at = self._dropped_warned
        if self.buffer.dropped > warned and time.monotonic() - warned_at > 60:
            log.warning(
                gettext(
                    "snapshot buffer full (snapshot.buffer_mb): %d oldest messages dropped so far"
                ),
                self.buffer.dropped,
            )
            self._dropped_warned = (self.buffer.dropped, time.monotonic())

    def close(self, wait: bool = True, within: float | None = None) -> None:
        """Write what is pending with the messages it has, then stop the writer;
        a writer not done ``within`` seconds is killed and its snapshots are lost
        (a stuck writer must not hold the collector's exit)."""
        for snap in self.pending:
            snap.end = min(snap.end, time.time_ns())
            self._futures.append(self._pool.submit(self._write, snap, dict(self.types)))
        self.pending = []
        if within is not None:
            _, late = futures.wait(self._futures, timeout=within)
            if late:
                log.error(gettext("snapshot writer not done within %.0f s at exit: killed"), within)
                self.writer.give_up()
        self._pool.shutdown(wait=wait)
        if wait:
            self.writer.close()

    # --- writer thread ------------------------------------------------------------------

    def _write(self, snap: Snapshot, types: dict[str, str]) -> None:
        try:
            self._write_file(snap, types)
        except WriterDied as exc:
            log.error(gettext("snapshot %s lost: %s"), snap.uid, exc)
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
        if self.guard is not None and self.guard.check(snap.size) >= TIGHT:
            self.guard.count("snapshots")
            log.info(gettext("snapshot %s dropped: the robot disk is (nearly) full"), snap.uid)
            return
        if not self._make_room(snap.size):
            log.warning(
                gettext("snapshot %s dropped: %.1f MB is more than the disk budget"),
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
        log.info(
            gettext("snapshot %s: %d messages on %d topics"), path.name, len(messages), len(topics)
        )

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
                log.warning(
                    gettext("disk budget for snapshots full: dropped the pending %s"), oldest.name
                )
        return True


def snapshot_topics(params: dict, graph: dict[str, list[str]], resolve) -> dict[str, str]:
    """{resolved topic: message type} of the snapshot topics published now."""
    names = [t.strip() for t in params["snapshot.topics"].split(",") if t.strip()]
    if not names:
        names = [params[f"topics.{key}"] for key in DEFAULT_TOPIC_PARAMETERS]
        names += OPTIONAL_TOPICS
        # The robot's own mode and reason topics tell what happened at a take-over.
        sources = mode_sources.parse(params.get("params.mode_sources", ""))
        names += [s.topic for s in sources.sources] if sources else []
        rules = reason_rules.parse(params.get("params.reason_rules", ""))
        names += [r.topic for r in rules.rules] if rules else []
    wanted = {}
    for name in names:
        if not name:
            continue
        topic = resolve(name)
        types = graph.get(topic)
        if types:
            wanted[topic] = types[0]
    return wanted
