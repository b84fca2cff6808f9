"""A full robot disk never stops the recording (issue 32): the spool on a small
file system the test mounts, the writer's order, a stuck snapshot writer at exit."""

import logging
import os
import queue
import subprocess
import time
import uuid
from datetime import UTC, datetime, timedelta

import pytest

from events.models import Segment
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.disk_guard import FULL, OK, TIGHT, DiskGuard
from rosbridge_app.collector.event_writer import EventWriter
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.replay import ReplayOrder
from rosbridge_app.collector.spool import Spool
from rosbridge_app.collector.spooler import Spooler
from telemetry.models import Pose

MB = 1024 * 1024


@pytest.fixture
def small_disk(tmp_path):
    """A 4 MB file system of its own (tmpfs), as on a robot whose disk others fill."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(mount)])
    if done.returncode != 0:
        pytest.skip("mounting a small file system needs root")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], check=False)


def _noise_png() -> bytes:
    import io

    from PIL import Image

    out = io.BytesIO()
    Image.frombytes("RGB", (220, 220), os.urandom(220 * 220 * 3)).save(out, "PNG")
    return out.getvalue()


NOISE = _noise_png()  # about 150 kB that no compression makes smaller


def _robot_second(t: datetime, second: int) -> list[Event]:
    """One second of a robot: GPS at 10 Hz, one map (incompressible, 150 kB)."""
    out = []
    for i in range(10):
        at = t + timedelta(seconds=second + i / 10)
        lat = 50.0 + (second * 10 + i) * 1e-5
        out.append(Event(ev.GPS_FIX, at, {"lon": 7.0, "lat": lat, "robot_stamp": at}))
    grid = {"frame": "map", "width": 2, "height": 2, "resolution": 0.1}
    grid.update(origin_x=0.0, origin_y=0.0, checksum=str(second))
    out.append(Event(ev.MAP, t + timedelta(seconds=second), grid, blob=NOISE))
    out.append(Event(ev.IMAGE, t + timedelta(seconds=second), {"master": None}, blob=b"x"))
    return out


@pytest.mark.django_db
def test_a_full_spool_holds_switches_and_thinned_positions_and_the_database_gets_them_all(
    small_disk, leg, media_root, caplog
):
    caplog.set_level(logging.INFO, "ftt.collector")
    spool = Spool(small_disk / "spool.sqlite3")
    guard = DiskGuard(spool.path, budget=None, headroom=0)
    guard.make_reserve()
    events = queue.Queue()
    spooler = Spooler(events, spool, guard)
    t0 = datetime.now(UTC)
    events.put(Event(ev.START, t0))
    switches = {0: "auto", 20: "ito", 40: "auto"}
    for second in range(60):
        if second in switches:
            events.put(Event(ev.MODE, t0 + timedelta(seconds=second), {"mode": switches[second]}))
        for event in _robot_second(t0, second):
            events.put(event)
        while not events.empty():
            spooler.spool_once(timeout=0)
    # 60 × 150 kB of maps never fit 2 MB: the spool filled, the recording went on.
    assert guard.level == FULL
    assert guard.describe().startswith("robot disk full since ")
    held = list(spooler.held.events)
    assert [e.kind for e in held].count(ev.MAP) == 1 and ev.IMAGE not in {e.kind for e in held}
    assert caplog.text.count("robot disk full") == 1  # once, not once per failed write
    assert "Traceback" not in caplog.text

    # The database is reachable: everything goes to it, without any free disk.
    event_writer = EventWriter(lambda: leg)
    order = ReplayOrder(spool, 500, held=spooler.held)
    while order.write_next(event_writer):
        pass
    assert len(spool) == 0 and len(spooler.held) == 0
    masters = Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start")
    assert [m.segment_type_id for m in masters] == ["auto", "ito", "auto"]
    stamps = sorted(Pose.objects.values_list("robot_stamp", flat=True))
    gaps = [(b - a).total_seconds() for a, b in zip(stamps, stamps[1:], strict=False)]
    assert stamps[0] - t0 < timedelta(seconds=0.2) and t0 + timedelta(seconds=58.5) < stamps[-1]
    assert max(gaps) <= 1.0  # thinned to the report's resolution, never a hole
    assert len(stamps) < 590  # thinned indeed

    # The spool has room again (the writer emptied it): back to it, said once.
    events.put(Event(ev.GPS_FIX, t0 + timedelta(seconds=61), {"lon": 7.0, "lat": 51.0}))
    deadline = time.monotonic() + 10
    while guard.level != OK and time.monotonic() < deadline:
        spooler.spool_once(timeout=0.1)
    assert guard.level == OK and "robot disk has room again" in caplog.text
    assert len(spool) + len(spooler.held) >= 1 and guard.describe() == ""


def test_a_stuck_snapshot_writer_does_not_hold_the_exit(tmp_path):
    from rosbridge_app.collector.blackbox import Blackbox
    from rosbridge_app.collector.params import SPECS

    params = {name: spec.default for name, spec in SPECS.items()}
    box = Blackbox(lambda event: None, {**params, "snapshot.before": 5.0, "snapshot.after": 0.0})
    box.directory = tmp_path
    box.types["/s"] = "std_msgs/msg/String"
    box.receive("/s", b"\x00\x01\x00\x00\x02\x00\x00\x00a\x00")
    child = box.writer.start()
    child.conn.poll(120)  # ready: its interpreter is up
    os.kill(child.pid, 19)  # SIGSTOP: a writer stuck on a full disk
    box.trigger(datetime.now(UTC), str(uuid.uuid4()), "test")
    time.sleep(0.01)
    box.poll()
    started = time.monotonic()
    box.close(within=1.0)
    assert time.monotonic() - started < 10  # not the writer's 60 s deadline, twice


def test_a_write_that_meets_a_full_disk_is_spool_full_and_stored_records_still_leave(small_disk):
    from rosbridge_app.collector.spool import SpoolFull

    spool = Spool(small_disk / "spool.sqlite3")
    guard = DiskGuard(spool.path)
    guard.make_reserve()
    spool.free_reserve = guard.release_reserve
    t = datetime.now(UTC)
    stored = [Event(ev.MODE, t, {"mode": "auto"})]
    spool.append(stored)
    # Another tool fills the disk between our check and our write.
    filler = small_disk / "other-tools.bin"
    with open(filler, "wb") as f, pytest.raises(OSError):
        while True:
            f.write(os.urandom(64 * 1024))
            f.flush()
    with pytest.raises(SpoolFull):
        for _ in range(20):
            spool.append([Event(ev.MAP, t, {}, blob=NOISE)])
    (row_id, event), *_ = spool.peek()
    assert event.kind == ev.MODE
    spool.remove([row_id])  # on the reserve, though nothing else fits
    assert len(spool) == 0 and not guard.reserve_path.exists()


@pytest.mark.parametrize("database_ok", [True, False])
def test_a_nearly_full_disk_drops_camera_frames_only_while_the_database_is_away(
    tmp_path, database_ok
):
    import shutil

    spool = Spool(tmp_path / "spool.sqlite3")
    # Less than twice the headroom free, more than the headroom: nearly full.
    free = shutil.disk_usage(tmp_path).free
    guard = DiskGuard(spool.path, budget=None, headroom=int(free / 1.5))
    events = queue.Queue()
    spooler = Spooler(events, spool, guard, database_ok=lambda: database_ok)
    frame = Event(ev.IMAGE, datetime.now(UTC), {"master": None}, blob=b"jpeg")
    events.put(Event(ev.GPS_FIX, frame.at, {"lon": 7.0, "lat": 50.0}))
    spooler.spool_once(timeout=0)
    assert guard.level == TIGHT
    events.put(frame)
    spooler.spool_once(timeout=0)
    kinds = [event.kind for _, event in spool.peek(10)]
    assert kinds == ([ev.GPS_FIX, ev.IMAGE] if database_ok else [ev.GPS_FIX])
    assert guard.given_up["frames"] == (0 if database_ok else 1)
