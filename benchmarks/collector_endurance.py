"""The collector over long times: a database outage, and a soak at full rate.

The benchmark robot (``ftt_simulate``: GPS 100 Hz, TF 50 Hz, 640×480 rgb8
camera 10 Hz, a 2000×2000 occupancy grid changing every second) drives while
the collector logs with the shipped parameters (default thinning).

``outage``: the collector reaches PostgreSQL through a TCP relay in this
process; the relay is cut for ``--minutes`` (every connection dropped, new
ones refused), as when the robot's link to the base station goes, then
restored. Prints how the spool grows (records and bytes per minute,
extrapolated to 2 hours) and what it holds by kind, the time from the restore
until the backlog is stored, the collector's own replay rate by kind (its log
line "backlog of N spooled records stored in ..."; the robot keeps driving
meanwhile), and when a mode switch published at the restore was stored, with
how many backlog records were still unwritten then (the order, not a timing),
the same for a second switch once a fifth of the backlog is written, and the
highest ``pending`` the collector showed (the GUI's "records not yet stored").
``--collector-root /work/main`` runs main's collector (A/B at the same load).

``soak``: ``--minutes`` at full rate; prints the collector's RSS every minute
and the growth over the second half.

``outage --fill``: the 2-hour outage without waiting 2 hours. Once the
relay is cut, the benchmark robot's next ``--minutes`` (the simulator's own
code on a clock run as fast as the machine allows) go through a collector
pipeline and the collector's spooler into the running collector's spool, as
the collector itself would have appended them; then the relay is restored
and the same figures are printed. The camera is simulated too but, with no
mode switch, leaves no records, as in the real drill.

``diskfull`` (issue 32): the benchmark robot, switching every 10 s, while
the collector's spool lies on a 6 MB file system of its own; the database is
cut until that disk is full, stays away ``--minutes`` (default 0.5) longer,
then comes back, and the robot drives 10 s more. Prints mode switches and
positions stored against published, the largest gap between stored positions,
how soon live data was stored after the restore, what the cockpit showed, and
whether the collector ran on. Needs root (it mounts a tmpfs).

``replay``: the writer alone, without ROS traffic: a spool of ``--records``
GPS fixes and local poses interleaved as the robot sends them (what a long
outage leaves, apart from the maps) is written by a starting collector;
prints records per second. ``--against /work/main`` runs the same replay
with that checkout's collector right after this one's and prints the two
figures side by side; ``--busy N`` keeps N busy loops (one core each)
running meanwhile, as a robot's own work does.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_endurance.py \\
        outage [--fill] | soak [--minutes N] | diskfull
        | replay [--records N] [--against /work/main] [--busy 2]

Issue 16's targets: a 2-hour outage with a documented spool size and replay at
>= 5 000 records/s; RSS flat over 1 hour. The load average is printed with
every figure (shared machine). PostGIS only (an embedded database has no
outage). Uses a throw-away vehicle and test event and deletes them afterwards.
"""

import argparse
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlsplit, urlunsplit

from collector_bench import MANAGE, ROBOT, Bench, load
from collector_diskfull import disk_full
from django.db import connection

from events.models import Segment
from rosbridge_app.models import Collector
from tests.support.diskfull import Relay

PAGE = os.sysconf("SC_PAGE_SIZE")


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def rss_mb(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return int(fields[21]) * PAGE / 2**20


class SpoolFile:
    def __init__(self, path: Path):
        self.path = path

    def records(self, upto: int | None = None) -> int:
        try:
            with sqlite3.connect(f"file:{self.path}?mode=ro", uri=True, timeout=5) as db:
                if upto is None:
                    return db.execute("SELECT count(*) FROM event").fetchone()[0]
                return db.execute("SELECT count(*) FROM event WHERE id <= ?", (upto,)).fetchone()[0]
        except sqlite3.Error:
            return -1

    def composition(self) -> tuple[int, dict[str, int]]:
        """The last id and the records by kind."""
        with sqlite3.connect(f"file:{self.path}?mode=ro", uri=True, timeout=5) as db:
            last = db.execute("SELECT coalesce(max(id), 0) FROM event").fetchone()[0]
            rows = db.execute("SELECT kind, count(*) FROM event GROUP BY kind ORDER BY 2 DESC")
            return last, dict(rows.fetchall())

    def megabytes(self) -> float:
        files = [self.path, Path(f"{self.path}-wal")]
        return sum(f.stat().st_size for f in files if f.exists()) / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drill", choices=("outage", "soak", "replay", "diskfull"))
    parser.add_argument("--records", type=int, default=100_000, help="replay: spooled records")
    parser.add_argument("--minutes", type=float, default=None, help="outage 120, soak 60")
    parser.add_argument(
        "--fill", action="store_true", help="outage: spool --minutes of the robot at once"
    )
    parser.add_argument("--keep-log", type=Path, help="copy the collector's log here at the end")
    parser.add_argument(
        "--collector-root",
        type=Path,
        help="run the collector from this checkout (A/B against main: /work/main)",
    )
    parser.add_argument(
        "--against", type=Path, help="replay: also run this checkout's collector, side by side"
    )
    parser.add_argument("--busy", type=int, default=0, help="replay: busy loops meanwhile")
    args = parser.parse_args()
    minutes = args.minutes or (120.0 if args.drill == "outage" else 60.0)
    if connection.vendor != "postgresql":
        sys.exit("needs FTT_DATABASE_URL=postgis://...")
    # Snapshots are part of what fills a robot's disk.
    bench = Bench(args.drill, **({} if args.drill == "diskfull" else {"snapshot.enabled": False}))
    if args.drill == "replay":
        trees = [("this tree", MANAGE)]
        if args.against:
            trees.append((str(args.against), [sys.executable, str(args.against / "manage.py")]))
        busy = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(args.busy)]
        try:
            rates = [(label, replay(bench, args.records, manage, label)) for label, manage in trees]
        finally:
            for loop in busy:
                loop.kill()
            bench.close()
        print(f"\nreplay of {args.records} records, {args.busy} busy loops:")
        for label, rate in rates:
            print(f"  {label:<40} {rate:>8.0f} records/s  [target >= 5000/s]")
        return
    if args.drill == "diskfull":
        try:
            disk_full(bench, args.minutes or 0.5)
        finally:
            bench.close()
        return
    env = {}
    relay = None
    if args.drill == "outage":
        url = urlsplit(os.environ["FTT_DATABASE_URL"])
        relay = Relay((url.hostname or "127.0.0.1", url.port or 5432))
        relay.start()
        netloc = f"{url.username}:{url.password}@127.0.0.1:{relay.port}"
        env["FTT_DATABASE_URL"] = urlunsplit(url._replace(netloc=netloc))
    spool_file = SpoolFile(bench.work / "spool.sqlite3")
    manage = MANAGE
    if args.collector_root:
        manage = [sys.executable, str(args.collector_root / "manage.py")]
    print(f"collector code: {manage[1]}")
    collector = bench.collector(spool_file.path, bench.work / "collector.log", env, manage)
    while not Collector.objects.filter(name=bench.key).exists():
        time.sleep(0.2)
    seconds = minutes * 60 + (90 if args.drill == "outage" else 0)
    if args.fill:
        seconds = 600
    robot = bench.robot(seconds, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    print(f"database: {connection.vendor} · {os.cpu_count()} cores · {load()}")
    try:
        mode = robot_mode(bench.leg)
        if args.drill == "outage":
            filler = (lambda: fill(bench, spool_file.path, minutes)) if args.fill else None
            log = bench.work / "collector.log"
            outage(relay, spool_file, minutes, bench.leg, mode, log, filler, bench.key)
        else:
            soak(collector, robot, minutes)
    finally:
        robot.terminate()
        robot.wait(30)
        collector.send_signal(2)
        collector.wait(120)
        if args.keep_log:
            shutil.copyfile(bench.work / "collector.log", args.keep_log)
        bench.close()


def robot_mode(leg):
    """AUTO until the collector has opened its segment (the simulator sends no mode)."""
    import rclpy
    from std_msgs.msg import Bool

    if not rclpy.ok():
        rclpy.init()
    node = rclpy.create_node("ftt_endurance")
    mode = node.create_publisher(Bool, "robot_mode", 10)
    started = time.monotonic()
    while not Segment.objects.masters().filter(leg=leg).exists():
        if time.monotonic() - started > 120:
            sys.exit("the collector opened no segment in 2 minutes")
        mode.publish(Bool(data=True))
        time.sleep(0.5)
    return mode


def outage(relay, spool_file, minutes, leg, mode, collector_log, filler=None, name="") -> None:
    from std_msgs.msg import Bool

    time.sleep(10)  # the robot is found and the first records are stored
    base = spool_file.records()
    relay.cut()
    cut_at = time.monotonic()
    print(f"outage begins: spool {base} records ({load()})")
    if filler is not None:
        filler()
    while filler is None and time.monotonic() - cut_at < minutes * 60:
        time.sleep(min(60.0, minutes * 60 - (time.monotonic() - cut_at)))
        elapsed = (time.monotonic() - cut_at) / 60
        print(
            f"  after {elapsed:5.1f} min: spool {spool_file.records()} records, "
            f"{spool_file.megabytes():.1f} MB ({load()})"
        )
    grown, megabytes = spool_file.records() - base, spool_file.megabytes()
    per_minute = grown / minutes
    print(
        f"spool grows {per_minute:.0f} records/min, {megabytes / minutes:.2f} MB/min; "
        f"2 h: {per_minute * 120:.0f} records, {megabytes / minutes * 120:.0f} MB (extrapolated)"
    )
    backlog_end, kinds = spool_file.composition()
    print(f"spool at the restore: {sum(kinds.values())} records ({_kinds(kinds)})")
    before = Segment.objects.masters().filter(leg=leg).count()
    relay.restore()
    restored = time.monotonic()
    # A switch at the restore, while the backlog waits to be replayed: when is
    # it in the database, and is that before the backlog is?
    mode.publish(Bool(data=False))
    published = time.monotonic()
    switch_stored = backlog_stored = None
    # A second switch once a fifth of the backlog is written: it waits for the
    # backlog slice being stored (collector/replay.py), the live side's worst case.
    total, mid, mid_stored, shown = sum(kinds.values()), None, None, 0
    while time.monotonic() - restored < 1800:
        t = time.monotonic()
        # What the GUI's collector line says ("N records not yet stored").
        row = Collector.objects.filter(name=name).values_list("pending", flat=True).first()
        shown = max(shown, row or 0)
        masters = Segment.objects.masters().filter(leg=leg).count()
        left = spool_file.records(upto=backlog_end)
        if switch_stored is None and masters > before:
            switch_stored = t
            # The order, not the timing: what of the backlog was still unwritten.
            left_behind = left
        if mid is not None and mid_stored is None and masters > before + 1:
            mid_stored, mid_left_after = t, left
        if mid is None and switch_stored is not None and 0 < left < total * 0.8:
            mode.publish(Bool(data=True))
            mid, mid_left = time.monotonic(), left
        if backlog_stored is None and left == 0:
            backlog_stored = t
        if None not in (switch_stored, backlog_stored) and (mid is None or mid_stored):
            break
        time.sleep(0.05)
    time.sleep(1.5)  # the collector logs the backlog when it has stored it
    log = collector_log.read_text(errors="replace")
    back = re.search(r"database back after (\d+) s", log)
    replayed = re.findall(r"backlog of (\d+) spooled records stored in ([\d.]+) s: (.*)", log)
    print(f"figures ({load()}); targets from issue 16:")
    if backlog_stored is not None:
        took = backlog_stored - restored
        print(
            f"  restore -> backlog of {sum(kinds.values())} stored: {took:.2f} s, "
            f"{sum(kinds.values()) / took:.0f} records/s including the reconnect"
        )
    for count, took, rest in replayed[-1:]:
        print(f"  replay in the collector: {count} records in {took} s: {rest}  [target >= 5000/s]")
    if not replayed:
        print("  replay in the collector: not logged (first in, first out)  [target >= 5000/s]")
    if switch_stored is None:
        print("  live mode switch: not stored in 30 min")
    else:
        order = f"{left_behind} of the backlog's records still in the spool then"
        print(
            f"  live mode switch published {published - restored:.1f} s after the restore: stored "
            f"{switch_stored - restored:.2f} s after the restore, {order}  "
            "[target: before the backlog, i.e. > 0 left]"
        )
    print(f"  the GUI's backlog (the collector's pending, highest seen after the restore): {shown}")
    if mid is None:
        print("  switch during the replay: not sent (the backlog went too fast to catch)")
    elif mid_stored is None:
        print("  switch during the replay: not stored in 30 min")
    else:
        print(
            f"  switch published during the replay ({mid_left} backlog records left): stored "
            f"{mid_stored - mid:.2f} s later, {mid_left_after} backlog records still unwritten"
        )
    if back:
        print(f"  (the collector said: database back after {back.group(1)} s of outage)")


def _kinds(kinds: dict) -> str:
    return ", ".join(f"{kind} {count}" for kind, count in kinds.items())


def replay(bench, records: int, manage=MANAGE, label: str = "this tree") -> float:
    from datetime import UTC, datetime, timedelta

    from rosbridge_app.collector import events as ev
    from rosbridge_app.collector.spool import Spool

    spool_file = SpoolFile(bench.work / f"replay-{len(list(bench.work.glob('replay-*')))}.sqlite3")
    spool = Spool(spool_file.path)
    t0 = datetime.now(UTC) - timedelta(hours=2)
    at = lambda i: t0 + timedelta(seconds=i * 0.1)  # noqa: E731
    events = [
        ev.Event(ev.START, t0),
        ev.Event(ev.MODE, t0, {"mode": "auto", "robot_stamp": None, "gps": None, "local": None}),
    ]
    for i in range(records):
        if i % 2:
            data = {"x": i * 0.01, "y": 0.0, "yaw": 0.0, "frame": "map", "robot_stamp": at(i)}
            events.append(ev.Event(ev.LOCAL_POSE, at(i), data))
        else:
            data = {"lon": 7.0, "lat": 50.0 + i * 1e-7, "alt": None, "status": 0}
            events.append(
                ev.Event(ev.GPS_FIX, at(i), {**data, "accuracy": None, "robot_stamp": at(i)})
            )
    for start in range(0, len(events), 5000):
        spool.append(events[start : start + 5000])
    spool.close()
    print(f"spooled {spool_file.records()} records, {spool_file.megabytes():.1f} MB ({load()})")
    started = time.monotonic()
    collector = bench.collector(spool_file.path, bench.work / "collector.log", manage=manage)
    first = None
    while spool_file.records() > 0 and time.monotonic() - started < 1800:
        left = spool_file.records()
        if first is None and 0 <= left < records:
            first = (time.monotonic(), left)
            cpu = cpu_seconds(collector.pid)
        time.sleep(0.1)
    done = time.monotonic()
    if first is not None:
        cpu = cpu_seconds(collector.pid) - cpu
    collector.send_signal(2)
    collector.wait(60)
    if first is None:
        print(f"{label}: nothing was replayed")
        return 0.0
    took = done - first[0]
    print(
        f"{label}: replay: {first[1]} records written in {took:.1f} s after the first batch: "
        f"{first[1] / took:.0f} records/s ({load()}); collector started "
        f"{first[0] - started:.1f} s before the first batch was written; the collector's "
        f"CPU meanwhile {cpu:.1f} s ({cpu / first[1] * 1e6:.0f} us per record)"
    )
    return first[1] / took


class _Into:
    """A publisher of the simulated robot that hands its messages to the pipeline,
    received at the robot's clock."""

    def __init__(self, handler, clock):
        self.handler, self.clock = handler, clock

    def publish(self, msg) -> None:
        self.handler(msg, self.clock.now())


class _Clock:
    def __init__(self, t: float):
        self.t = t

    def now(self):
        from datetime import UTC, datetime

        return datetime.fromtimestamp(self.t, UTC)


def fill(bench, path: Path, minutes: float) -> None:
    """The spool a collector cut off from the database for ``minutes`` leaves."""
    import queue

    import rclpy
    from std_msgs.msg import Bool

    from rosbridge_app.collector import events as ev
    from rosbridge_app.collector import params as P
    from rosbridge_app.collector.pipeline import Pipeline
    from rosbridge_app.collector.simulator import SimConfig, SimulatedRobot
    from rosbridge_app.collector.spool import Spool
    from rosbridge_app.collector.spooler import SPOOL_INTERVAL, Spooler

    options = dict(zip(ROBOT[::2], ROBOT[1::2], strict=True))
    width, height = (int(v) for v in options["--camera-size"].split("x"))
    config = SimConfig(
        gps_rate=float(options["--gps-rate"]),
        tf_rate=float(options["--tf-rate"]),
        camera_rate=float(options["--camera-rate"]),
        camera_width=width,
        camera_height=height,
        map_size=int(options["--map-size"]),
        map_rate=float(options["--map-rate"]),
        mode_rate=float(options["--mode-rate"]),
    )
    if not rclpy.ok():
        rclpy.init()
    started = time.monotonic()
    clock = _Clock(time.time() - minutes * 60)
    robot = SimulatedRobot(config, "ftt_backlog_fill", clock=lambda: clock.t)
    events = queue.Queue()
    pipeline = Pipeline(events.put, P.read_file(bench.params))
    spool = Spool(path)
    spooler = Spooler(events, spool)
    robot.pub_fix = _Into(pipeline.on_fix, clock)
    robot.pub_tf = _Into(pipeline.on_tf, clock)
    robot.pub_tf_static = _Into(lambda m, at: pipeline.on_tf(m, at, static=True), clock)
    robot.pub_map = _Into(pipeline.on_grid, clock)
    robot.pub_image = _Into(pipeline.on_image, clock)
    robot._publish_static()
    robot.publish_map()
    # The collector logs in the mode robot_mode() sends: its start and that mode
    # are in the database already, and the pipeline records nothing before them.
    pipeline.start_logging(clock.now())
    pipeline.on_mode(Bool(data=True), clock.now())
    kept = []
    while not events.empty():
        event = events.get()
        if event.kind not in (ev.START, ev.MODE):
            kept.append(event)
    for event in kept:
        events.put(event)
    robot.t0 = clock.t
    step = 1 / config.gps_rate
    every = {
        robot.publish_tf: round(config.gps_rate / config.tf_rate),
        robot.publish_image: round(config.gps_rate / config.camera_rate),
        robot.publish_map: round(config.gps_rate / config.map_rate),
        lambda: pipeline.tick(clock.now()): round(config.gps_rate),
    }
    spool_every = max(1, round(SPOOL_INTERVAL / step))
    begin = clock.t
    for i in range(round(minutes * 60 * config.gps_rate)):
        clock.t = begin + i * step
        robot.publish_fix()
        for publish, n in every.items():
            if i % n == 0:
                publish()
        if i % spool_every == 0:
            while spooler.spool_once(timeout=0):
                pass
        if i % round(600 * config.gps_rate) == 0 and i:
            print(f"  filled {i * step / 60:.0f} min ({time.monotonic() - started:.0f} s)")
    while spooler.spool_once(timeout=0):
        pass
    spool.close()
    robot.destroy_node()
    print(f"filled {minutes:g} min of the robot in {time.monotonic() - started:.0f} s ({load()})")


def soak(collector, robot, minutes) -> None:
    start = time.monotonic()
    curve = []
    while robot.poll() is None and time.monotonic() - start < minutes * 60:
        curve.append(((time.monotonic() - start) / 60, rss_mb(collector.pid)))
        print(f"  {curve[-1][0]:5.1f} min: collector RSS {curve[-1][1]:.0f} MB ({load()})")
        time.sleep(60 if minutes > 5 else 10)
    curve.append(((time.monotonic() - start) / 60, rss_mb(collector.pid)))
    half = [rss for t, rss in curve if t >= curve[-1][0] / 2]
    print(
        f"RSS: start {curve[0][1]:.0f} MB, max {max(r for _, r in curve):.0f} MB, "
        f"end {curve[-1][1]:.0f} MB; second half {half[0]:.0f} → {half[-1]:.0f} MB "
        f"({load()})"
    )


if __name__ == "__main__":
    main()
