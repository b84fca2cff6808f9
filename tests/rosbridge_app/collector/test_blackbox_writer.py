"""Snapshot files are built by a child process: the collector's own threads only
hand it the messages, and a writer that dies neither stops the collector nor
delivers half a file."""

import os
import re
import signal
import time
from datetime import UTC, datetime
from pathlib import Path

import pytest
from mcap.reader import make_reader

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.blackbox import Blackbox
from rosbridge_app.collector.params import SPECS

TOPIC, TYPE = "/many", "std_msgs/msg/UInt8MultiArray"
# Many small messages: building the file is per-message Python work (0.2 s of CPU
# here), long enough to see the file being written and to kill its writer.
COUNT = 20_000


def busy_box(tmp_path: Path, sent: list) -> Blackbox:
    values = {name: spec.default for name, spec in SPECS.items()}
    values.update({"snapshot.before": 20.0, "snapshot.after": 0.0})
    box = Blackbox(sent.append, values)
    box.directory = tmp_path
    box.types[TOPIC] = TYPE
    return box


def take_snapshot(box: Blackbox, first: int = 0) -> None:
    """COUNT messages of the last 10 s (each carries its number), then a window
    that has passed at once; poll() hands it to the writer."""
    start = time.time_ns() - 10 * 10**9
    for i in range(first, first + COUNT):
        # CDR of UInt8MultiArray: empty layout, then 4 data bytes.
        data = b"\x00\x01\x00\x00" + bytes(8) + b"\x04\x00\x00\x00" + i.to_bytes(4, "little")
        box.receive(TOPIC, data, start + (i - first) * 10**9 // COUNT * 10)
    box.trigger(datetime.now(UTC), None, "test")
    time.sleep(0.01)
    box.poll()


def children() -> list[int]:
    tasks = Path("/proc/self/task").glob("*/children")
    return [int(pid) for task in tasks for pid in task.read_text().split()]


def opened_by(path: Path) -> list[int]:
    """This process and those of its children that have ``path`` open."""
    found = []
    for pid in [os.getpid(), *children()]:
        try:
            fds = os.listdir(f"/proc/{pid}/fd")
            if any(os.readlink(f"/proc/{pid}/fd/{fd}") == str(path) for fd in fds):
                found.append(int(pid))
        except OSError:  # gone, or a descriptor closed meanwhile
            continue
    return found


def writer_at_work(directory: Path, not_pid: int | None = None) -> tuple[Path, int]:
    """(the file being written, the process writing it), as soon as there is one."""
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        for part in directory.glob(".*.part"):
            writers = [p for p in opened_by(part.resolve()) if p != not_pid]
            if writers:
                return part, writers[0]
        time.sleep(0.005)
    raise AssertionError("no snapshot file was being written")


def messages_in(path) -> list[int]:
    """The number in each message, in the order of the file (read without decoding:
    a standard reader's ROS 2 decoding of every message is what the other tests do)."""
    with open(path, "rb") as f:
        return [int.from_bytes(m.data[-4:], "little") for _, _, m in make_reader(f).iter_messages()]


def kill_writer(directory: Path, not_pid: int | None = None) -> int:
    _, writer = writer_at_work(directory, not_pid)
    os.kill(writer, signal.SIGKILL)
    return writer


@pytest.fixture
def writing(tmp_path):
    """(black box, events it sent) with a large snapshot handed to its writer."""
    sent = []
    box = busy_box(tmp_path, sent)
    take_snapshot(box)
    yield box, sent
    box.close()


def test_the_file_is_built_by_a_child_process_not_by_the_collector(writing, tmp_path):
    box, sent = writing
    part, writer = writer_at_work(tmp_path)
    assert writer != os.getpid()
    assert writer in children()
    assert os.getpid() not in opened_by(part.resolve())
    box.close()
    (event,) = sent
    assert event.kind == ev.RECORDING
    assert messages_in(event.data["path"]) == list(range(COUNT))
    assert event.data["topics"] == {TOPIC: {"type": TYPE, "count": COUNT}}


def test_a_killed_writer_is_logged_and_replaced_and_the_file_is_whole(writing, tmp_path, caplog):
    box, sent = writing
    writer = kill_writer(tmp_path)
    box.close()
    assert f"snapshot writer process (pid {writer}) died" in caplog.text
    (event,) = sent  # written again by a new writer, complete
    assert messages_in(event.data["path"]) == list(range(COUNT))
    assert not list(tmp_path.glob(".*.part"))


def test_a_snapshot_whose_writers_keep_dying_is_lost_and_the_next_one_is_written(
    writing, tmp_path, caplog
):
    box, sent = writing
    kill_writer(tmp_path, not_pid=kill_writer(tmp_path))
    box._pool.submit(lambda: None).result()  # the writer thread has given up
    assert "snapshot lost" in caplog.text
    assert sent == []  # nothing to deliver, so no Recording row
    assert not list(tmp_path.glob("*.mcap")) and not list(tmp_path.glob(".*.part"))

    box.buffer.items.clear()
    box.buffer.size = 0
    take_snapshot(box, first=COUNT)
    box.close()
    (event,) = sent
    assert messages_in(event.data["path"]) == list(range(COUNT, 2 * COUNT))


def numbered(numbers: range, size: int = 5_000) -> list[bytes]:
    """UInt8MultiArray messages of ``size`` data bytes ending in their number."""
    head = b"\x00\x01\x00\x00" + bytes(8) + size.to_bytes(4, "little")
    return [head + bytes(size - 4) + i.to_bytes(4, "little") for i in numbers]


def snapshot_of(box: Blackbox, numbers: range) -> None:
    """A window of the last second with those messages, handed to the writer,
    and back once the writer thread is done with it (written, or given up)."""
    box.buffer.items.clear()
    box.buffer.size = 0
    start = time.time_ns() - 10**9
    for k, data in enumerate(numbered(numbers)):
        box.receive(TOPIC, data, start + k * 1000)
    box.trigger(datetime.now(UTC), None, "test")
    time.sleep(0.01)
    box.poll()
    box._pool.submit(lambda: None).result()


@pytest.fixture
def quick_box(tmp_path):
    """A black box whose writer is given 3 s (+1 s per MB: 1 MB windows)."""
    sent = []
    values = {name: spec.default for name, spec in SPECS.items()}
    values.update({"snapshot.before": 5.0, "snapshot.after": 0.0, "snapshot.write_timeout": 3.0})
    box = Blackbox(sent.append, values)
    box.directory = tmp_path
    box.types[TOPIC] = TYPE
    yield box, sent
    box.close()


def gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_a_stuck_writer_is_killed_after_its_time_and_the_next_one_writes_the_file(
    quick_box, tmp_path, caplog
):
    box, sent = quick_box
    snapshot_of(box, range(0, 200))
    stuck = box.writer.pid
    os.kill(stuck, signal.SIGSTOP)  # alive, but does nothing any more
    # The hand-over itself waits for the stopped child to take the window.
    snapshot_of(box, range(200, 400))
    assert f"snapshot writer process (pid {stuck}) was stuck" in caplog.text
    assert gone(stuck)
    assert box.writer.pid != stuck
    assert [messages_in(e.data["path"]) for e in sent] == [list(range(200)), list(range(200, 400))]
    assert not list(tmp_path.glob(".*.part"))


def test_a_snapshot_whose_writers_are_stuck_is_lost_and_the_next_one_is_written(
    quick_box, tmp_path, caplog, monkeypatch
):
    from rosbridge_app.collector import snapshot_writer

    box, sent = quick_box
    started = snapshot_writer.WriterChild.__init__

    def stopped_at_start(child):
        started(child)
        os.kill(child.pid, signal.SIGSTOP)

    monkeypatch.setattr(snapshot_writer, "START_TIMEOUT", 3.0)
    monkeypatch.setattr(snapshot_writer.WriterChild, "__init__", stopped_at_start)
    snapshot_of(box, range(0, 200))
    stuck = [int(pid) for pid in re.findall(r"pid (\d+)\) was stuck", caplog.text)]
    assert len(stuck) == 2 and all(gone(pid) for pid in stuck)
    assert "snapshot lost" in caplog.text
    assert sent == []  # nothing to deliver, so no Recording row
    assert not list(tmp_path.glob("*.mcap")) and not list(tmp_path.glob(".*.part"))

    monkeypatch.undo()
    snapshot_of(box, range(200, 400))
    (event,) = sent
    assert messages_in(event.data["path"]) == list(range(200, 400))
