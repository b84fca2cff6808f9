"""The full-disk drill (issue 32), shared by its test and by
``benchmarks/collector_endurance.py diskfull``: the benchmark robot drives and
switches modes, the collector's spool lies on a small file system of its own,
the database is cut (a TCP relay) until the disk is full, stays away a while
longer, then comes back. The drill counts what the robot published (a
listener of its own) against what the database holds."""

import socket
import subprocess
import threading
import time
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

# The benchmark robot of collector_bench.py, switching modes.
ROBOT = [
    "--gps-rate",
    "100",
    "--tf-rate",
    "50",
    "--camera-rate",
    "10",
    "--camera-size",
    "640x480",
    "--map-size",
    "2000",
    "--map-rate",
    "1",
    "--mode-rate",
    "2",
]


class Relay(threading.Thread):
    """A TCP relay to the database that can be cut and restored."""

    def __init__(self, target: tuple[str, int]):
        super().__init__(daemon=True)
        self.target = target
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.up = True
        self.sockets: set[socket.socket] = set()
        self.lock = threading.Lock()

    def run(self):
        while True:
            client, _ = self.server.accept()
            if not self.up:
                client.close()
                continue
            try:
                upstream = socket.create_connection(self.target, timeout=5)
            except OSError:
                client.close()
                continue
            with self.lock:
                self.sockets.update((client, upstream))
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pump, args=(a, b), daemon=True).start()

    def _pump(self, source, sink):
        try:
            while data := source.recv(65536):
                sink.sendall(data)
        except OSError:
            pass
        for s in (source, sink):
            try:
                s.close()
            except OSError:
                pass

    def cut(self):
        self.up = False
        with self.lock:
            for s in self.sockets:
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
            self.sockets.clear()

    def restore(self):
        self.up = True


@contextmanager
def small_filesystem(path: Path, megabytes: int):
    """A tmpfs of ``megabytes`` at ``path`` (root only): a robot disk others have filled."""
    path.mkdir(parents=True, exist_ok=True)
    subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={megabytes}m", "tmpfs", str(path)], check=True
    )
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


class Listener:
    """What the robot published, heard beside the collector: mode changes and fixes.

    A change is timed by its publisher's send time (the DDS source timestamp),
    the time the collector stores: this process's own callbacks may run
    seconds late on a busy machine."""

    def __init__(self, node):
        from sensor_msgs.msg import NavSatFix
        from std_msgs.msg import Bool

        from rosbridge_app.collector.mode_timing import sent_at
        from rosbridge_app.collector.modes import AUTO, ITO

        self.changes: list[tuple[float, str]] = []
        self.fixes: list[float] = []
        self.counting = True

        def on_mode(msg, info):
            mode = AUTO if msg.data else ITO
            if self.counting and (not self.changes or self.changes[-1][1] != mode):
                sent = sent_at(info)
                self.changes.append((sent.timestamp() if sent else time.time(), mode))

        def on_fix(msg):
            if self.counting:
                self.fixes.append(time.time())

        node.create_subscription(Bool, "robot_mode", on_mode, 10)
        node.create_subscription(NavSatFix, "gps_fix", on_fix, 100)


def _aware(t: float) -> datetime:
    return datetime.fromtimestamp(t, UTC)


def run(*, relay, leg, name, log: Path, listener, full_seconds, after_seconds, alive, say=print):
    """The drill; ``alive()`` tells whether the collector still runs. Returns its figures."""
    from events.models import Segment
    from rosbridge_app.models import Collector
    from telemetry.models import Pose

    def wait(predicate, seconds, what):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if value := predicate():
                return value
            time.sleep(0.1)
        raise TimeoutError(f"{what} not within {seconds:.0f} s")

    poses = Pose.objects.filter(segment__leg=leg)
    wait(lambda: poses.exists(), 120, "the first stored position")
    figures = {"collector exited": False}
    relay.cut()
    cut = time.time()
    say("database cut; waiting for the spool's disk to fill")
    wait(lambda: "robot disk full" in log.read_text(errors="replace"), 300, "a full disk")
    full = time.time()
    figures["disk full after"] = full - cut
    say(
        f"disk full {figures['disk full after']:.0f} s after the cut; "
        f"database away {full_seconds} s more"
    )
    time.sleep(full_seconds)
    relay.restore()
    up = time.time()
    shown = set()

    def live_stored():
        row = Collector.objects.filter(name=name).values_list("disk", flat=True).first()
        if row:
            shown.add(row)
        return poses.filter(robot_stamp__gt=_aware(up)).exists()

    wait(live_stored, 60, "a live position after the restore")
    figures["live stored after"] = time.time() - up
    time.sleep(after_seconds)
    listener.counting = False
    end = time.time()
    wait(
        lambda: Collector.objects.filter(name=name, pending=0).exists() or None,
        120,
        "the backlog written",
    )
    figures["collector exited"] = not alive()

    def lost():
        masters = Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start")
        stored = [(m.start.timestamp(), m.segment_type_id) for m in masters]
        missing = [
            (round(t - cut, 1), mode)
            for t, mode in listener.changes[1:]
            if not any(mode == kind and abs(start - t) < 1.5 for start, kind in stored)
        ]
        return missing, stored

    # A switch heard just before the count stopped may still be on its way to
    # the database: it is lost only if it is not there within the wait.
    try:
        wait(lambda: not lost()[0], 30, "every switch stored")
    except TimeoutError:
        pass
    missing, stored = lost()
    stamps = sorted(
        s.timestamp()
        for s in poses.filter(robot_stamp__lte=_aware(end)).values_list("robot_stamp", flat=True)
    )
    first = listener.fixes[0] if listener.fixes else end
    inside = [s for s in stamps if s >= first]
    gaps = [b - a for a, b in zip(inside, inside[1:], strict=False)]
    figures.update(
        {
            "switches published": len(listener.changes) - 1,
            "switches lost": len(missing),
            "lost switches (s after the cut, mode)": missing,
            "switches while the disk was full": sum(
                1 for t, _ in listener.changes if full < t < up
            ),
            "masters in order": [kind for _, kind in stored],
            "positions published": len(listener.fixes),
            "positions stored": len(inside),
            "largest gap between stored positions": max(gaps, default=0.0),
            "cockpit showed": sorted(shown),
            "run": end - first,
        }
    )
    return figures
