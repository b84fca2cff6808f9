"""What ftt_collect sustains on this machine, into the configured database.

A simulated robot (ftt_simulate, its own process) publishes GPS at 100 Hz, TF
at 50 Hz, a 640×480 camera at 10 Hz (JPEG of about 60 kB on image_compressed,
or ``--camera raw`` rgb8 on image) and a 2000×2000 occupancy grid that changes
every second; this script publishes a mode switch every 2 s and times each one
from publish to its committed master row.  The collector runs as its own
process with the shipped parameters (map stored at most once a second).
Prints what was published and received, rows written, the collector's CPU and
memory, the spool backlog, the mode-to-row delay, and how long a GUI command
(set parameters, issued through the database between two mode switches) takes
to be carried out while the robot is this busy.

The black box (issue 15) runs with its default topics (mode, GPS, TF, static
TF, compressed camera; the raw camera with ``--camera raw``) and the default
20 s before; ``after`` is 3.5 s so that a run has many snapshots.  With
``--snapshot alternate`` (default) it is switched on and off every ``--phase``
seconds through the GUI command path, so the buffer's CPU share is the
difference of the on and off phases of one run, under the same load of the
shared machine, with the same switches in both.

Whether writing a snapshot delays mode or pose recording: a thread watches the
pending directory every 5 ms (the writer process's ``.part`` file, then the
finished file until the database writer has stored it: one "write").  Each
mode switch is published at a chosen moment: with the black box on,
alternately between writes ("on, idle") and just as a write begins, the file
being built or the finished file about to be stored ("during a write"),
balanced by the direction of the switch (each switch to ITO starts the
snapshot written ``after`` seconds later); with it off, at once.  Every
switch comes at least 3.2 s after the previous one, so that each stores a full
buffer of camera frames (3, one a second) and the groups differ by the write
only (sooner, a switch carries fewer frames and is stored quicker).  GPS
fixes are grouped the same way by their stamp (the simulator's publish time).
Off, idle and write samples are interleaved in one run, so they share the
machine's load.  The last lines print p50 and p95 per group and the verdicts:
during a write, p50 and p95 within 25 % (+ 20 ms) of on-idle; the black box's
CPU (95 % bound) at most 10 % of one core.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_throughput.py \
        [--seconds 200] [--snapshot alternate|on|off] [--phase 40] [--camera jpeg|raw] \
        [--map-rate 1] [--ros-domain N] [--latency-only] [--code OTHER_CHECKOUT]

Also prints first the black box's own cost for 60 s of that traffic, fed
straight into Blackbox.receive in this process (``--buffer-only``: only that;
``--latency-only`` skips it).

``--gps-hz 1000`` measures something else: GPS alone at that rate with
thinning off and RELIABLE QoS (everything else as shipped, the black box
included), ``--gps-count`` fixes published by this script, and checks that
every one of them became a row: published / received / stored, the rate the
collector kept up with, how long the last rows took, and its CPU.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_throughput.py \
        --gps-hz 1000 [--gps-count 30000] [--publisher-depth 1000]

Uses a throw-away vehicle and test event in that database and deletes them
afterwards.  Sets its own ROS domain (40-59) and loopback discovery.
"""

import argparse
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from datetime import UTC, datetime
from pathlib import Path

# collector_bench sets the ROS domain and discovery range and sets Django up.
import collector_bench
from collector_bench import MANAGE, Bench
from django.db import connection
from django.db.models import Max

from events.models import Segment
from rosbridge_app.collector import params as P
from rosbridge_app.models import Collector, CollectorCommand
from rosbridge_app.services.collectors import issue_command
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording

TICKS = os.sysconf("SC_CLK_TCK")


def proc_sample(pid: int) -> tuple[float, int]:
    """(CPU seconds used so far, RSS bytes) of a process, from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    cpu = (int(fields[11]) + int(fields[12])) / TICKS
    rss = int(fields[21]) * os.sysconf("SC_PAGE_SIZE")
    return cpu, rss


def percentile(values, q):
    values = sorted(values)
    if not values:
        return float("nan")
    k = (len(values) - 1) * q
    lo, hi = int(k), min(int(k) + 1, len(values) - 1)
    return values[lo] + (values[hi] - values[lo]) * (k - lo)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=200.0)
    parser.add_argument(
        "--reliable",
        action="store_true",
        help="Subscribe GPS and camera RELIABLE (params.sensor_reliable).",
    )
    parser.add_argument("--camera", choices=("jpeg", "raw"), default="jpeg")
    parser.add_argument(
        "--map-rate",
        type=float,
        default=1.0,
        help="Changed 2000×2000 maps per second (0: one latched map); rendering them "
        "is most of the collector's CPU and of its spread.",
    )
    parser.add_argument("--snapshot", choices=("alternate", "on", "off"), default="alternate")
    parser.add_argument(
        "--phase",
        type=float,
        default=40.0,
        help="Seconds per on/off phase; longer than before + after, so that most "
        "snapshots have a full window.",
    )
    parser.add_argument(
        "--snapshot-after",
        type=float,
        default=3.5,
        help="Longer than the camera frames' buffer (3 × 1 s): the switch published as a "
        "write begins carries a full buffer, like every other switch.",
    )
    parser.add_argument(
        "--ros-domain",
        type=int,
        help="ROS domain of the run (default 40-59 from the pid; give your own on a "
        "machine where others run this benchmark too).",
    )
    parser.add_argument(
        "--buffer-only",
        action="store_true",
        help="Only the black box's own cost, in this process, without ROS or a database.",
    )
    parser.add_argument(
        "--latency-only",
        action="store_true",
        help="Skip the black box's own cost (two minutes): only the run with the collector.",
    )
    parser.add_argument(
        "--code",
        type=Path,
        help="Run ftt_collect from this checkout (A/B against other code, same database).",
    )
    parser.add_argument("--gps-hz", type=float, default=0.0)
    parser.add_argument("--gps-count", type=int, default=30_000)
    parser.add_argument("--publisher-depth", type=int, default=1000)
    args = parser.parse_args()
    load_before = os.getloadavg()
    if args.gps_hz:
        lossless_gps(args.gps_hz, args.gps_count, args.publisher_depth)
        return
    if args.ros_domain is not None:
        os.environ["ROS_DOMAIN_ID"] = str(args.ros_domain)
    if args.code is not None:
        collector_bench.MANAGE = [sys.executable, str(args.code.resolve() / "manage.py")]
    if not args.latency_only:
        buffer_cost()
        writer_stall()
        subscription_cost()
    if args.buffer_only:
        print(f"load average (1, 5, 15 min): {load(load_before)}")
        return

    import rclpy
    from std_msgs.msg import Bool

    camera = {
        "jpeg": {"topics.image": "", "topics.image_compressed": "image_compressed"},
        # The default snapshot list has the compressed camera only.
        "raw": {"topics.image": "image", "snapshot.topics": "robot_mode, gps_fix, /tf, image"},
    }[args.camera]
    bench, collector = start_bench(
        "throughput",
        **{
            "params.send_map_period": 1.0,
            "params.sensor_reliable": args.reliable,
            "snapshot.enabled": args.snapshot != "off",
            "snapshot.after": args.snapshot_after,
            **camera,
        },
    )
    key, leg, work, env = bench.key, bench.leg, bench.work, bench.env
    manage = MANAGE
    writing = SnapshotWatch(work / "spool.snapshots")
    robot = subprocess.Popen(
        [
            *manage,
            "ftt_simulate",
            "--gps-rate",
            "100",
            "--tf-rate",
            "50",
            "--camera-rate",
            "10",
            "--camera-size",
            "640x480",
            "--camera-format",
            args.camera,
            "--map-size",
            "2000",
            "--map-rate",
            str(args.map_rate),
            "--mode-rate",
            "0",
            "--duration",
            str(args.seconds),
            "--wait-for-subscriber",
            "20",
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )

    rclpy.init()
    node = rclpy.create_node("ftt_benchmark")
    mode = node.create_publisher(Bool, "robot_mode", 10)
    while mode.get_subscription_count() == 0:
        time.sleep(0.05)
    # The simulator takes seconds to start on a loaded machine: measure from
    # its first messages on, or the first phase would lack its traffic.
    while not Collector.objects.get(name=key).inputs.get("gps_fix", {}).get("count"):
        time.sleep(0.1)
    writing.start()
    phases = Phases(args.snapshot, args.phase)
    values = P.read_file(bench.params)
    frames = values["params.image_buffer_size"] * values["params.image_buffer_step"]
    switches = Switches(leg, writing, phases, args.snapshot_after, frames + 0.2)
    poses = PoseDelays(leg, writing, phases, switches)
    poses.start()
    cpu_by_phase: dict[bool, list[float]] = {True: [], False: []}
    command_delays, cpu_samples, rss_max, pending_max = [], [], 0, 0
    record = Collector.objects.get(name=key)
    cpu0, _ = proc_sample(collector.pid)
    t0 = time.monotonic()
    last_cpu, last_t = cpu0, t0

    def sample() -> None:
        nonlocal last_cpu, last_t, record, pending_max, rss_max
        now = time.monotonic()
        cpu, rss = proc_sample(collector.pid)
        rss_max = max(rss_max, rss)
        if now - last_t >= 1.0:
            share = (cpu - last_cpu) / (now - last_t)
            cpu_samples.append(share)
            # Subscribing and unsubscribing take up to a tick after a toggle.
            if phases.settled(time.time() - (now - last_t)):
                cpu_by_phase[phases.enabled].append(share)
            last_cpu, last_t = cpu, now
            record = Collector.objects.filter(name=key).first()
            pending_max = max(pending_max, record.pending if record else 0)

    try:
        while robot.poll() is None:
            sample()
            if phases.due():
                timed_command(record, {"snapshot.enabled": not phases.enabled})
                phases.toggle()
            elif time.monotonic() - t0 < args.seconds - 5:
                switches.next(mode, sample)
                command_delays.append(timed_command(record))
            else:
                time.sleep(0.05)
        writing.stop()
        poses.stop()
    except BaseException:
        for process in (robot, collector):
            process.kill()
        raise
    elapsed = time.monotonic() - t0
    published = robot.stdout.read()
    collector.send_signal(2)
    collector.wait(60)
    load_after = os.getloadavg()
    cpu_total = proc_sample_safe(cpu0, elapsed, cpu_samples)
    record = Collector.objects.get(name=key)
    counts = {k: v["count"] for k, v in record.inputs.items()}
    rows = {
        "GPS poses": Pose.objects.filter(segment__leg=leg).count(),
        "local poses": LocalPose.objects.filter(segment__leg=leg).count(),
        "maps": MapImage.objects.filter(shift=leg.shift).count(),
        "images": Image.objects.filter(segment__leg=leg).count(),
        "master segments": Segment.objects.masters().filter(leg=leg).count(),
        "snapshots": Recording.objects.filter(segment__leg=leg).count(),
    }
    snapshots = list(Recording.objects.filter(segment__leg=leg))
    snapshot_mb = sum(r.size for r in snapshots) / 2**20
    in_snapshots: dict[str, int] = {}
    for snapshot in snapshots:
        for topic, info in snapshot.topics.items():
            in_snapshots[topic] = in_snapshots.get(topic, 0) + info["count"]
    spool_left = record.pending
    qos = "RELIABLE" if args.reliable else "BEST_EFFORT"
    print(
        f"database: {connection.vendor} · {os.cpu_count()} cores · {elapsed:.0f} s run · "
        f"sensor QoS {qos} · camera {args.camera} · black box {args.snapshot}"
    )
    print(f"load average (1, 5, 15 min): before {load(load_before)}, after {load(load_after)}")
    print(f"published by the robot: {published.strip().splitlines()[-1]}")
    print(f"received by the collector: {counts}")
    match = re.search(r"\{.*\}", published)
    image_topic = {"jpeg": "image_compressed", "raw": "image"}[args.camera]
    if match:
        sent = eval(match.group(0), {})  # our own simulator's printed dict
        for name, topic in (
            ("gps", "gps_fix"),
            ("tf", "tf"),
            ("image", image_topic),
            ("map", "map"),
        ):
            got = counts.get(topic, 0)
            print(
                f"  {name:5s}: {got}/{sent[name]} received ({100 * got / max(1, sent[name]):.1f} %)"
            )
    print(f"rows written: {rows}")
    print(
        f"black box: {rows['snapshots']} snapshots, {snapshot_mb:.0f} MB, "
        f"{writing.seen} writes seen, messages {in_snapshots}"
    )
    print(
        f"collector CPU: mean {100 * statistics.mean(cpu_samples):.0f} % of one core, "
        f"max {100 * max(cpu_samples):.0f} %; total {cpu_total}"
    )
    if len(cpu_by_phase[True]) > 1 and len(cpu_by_phase[False]) > 1:
        on, off = (statistics.mean(cpu_by_phase[k]) for k in (True, False))
        # 95 % interval of the difference of the means (the seconds as samples).
        error = 1.96 * math.sqrt(
            sum(statistics.variance(v) / len(v) for v in cpu_by_phase.values())
        )
        print(
            f"collector CPU with the black box on: {100 * on:.1f} % "
            f"(n={len(cpu_by_phase[True])} s), off: {100 * off:.1f} % "
            f"(n={len(cpu_by_phase[False])} s); the black box adds {100 * (on - off):.1f} "
            f"± {100 * error:.1f} % of one core (buffer, snapshot writing and storing); "
            f"medians {100 * statistics.median(cpu_by_phase[True]):.1f} % and "
            f"{100 * statistics.median(cpu_by_phase[False]):.1f} %"
        )
        worst = 100 * (on - off + error)
        print(
            f"VERDICT black-box CPU: adds {100 * (on - off):.1f} % of one core, at most "
            f"{worst:.1f} % (95 %) — target ≤ 10 %: {'MET' if worst <= 10 else 'NOT MET'}"
        )
    print(f"collector RSS: max {rss_max / 2**20:.0f} MB")
    print(f"spool backlog: max {pending_max} records, {spool_left} left after exit")
    print(spread("GUI command issued → carried out by the collector", command_delays))
    print(
        f"mode switches published while a snapshot was being built / stored: "
        f"{switches.stages['building']} / {switches.stages['storing']}; "
        f"published between writes but one began before the row: {len(switches.delays['mixed'])}"
    )
    for stage, values in sorted(switches.by_stage.items()):
        print(spread(f"  mode message → master row, published while {stage}", values))
    print(f"load average (1, 5, 15 min) at the end: {load(os.getloadavg())}")
    print(
        verdict({"mode message → master row": switches.delays, "GPS fix → pose row": poses.delays})
    )
    node.destroy_node()
    rclpy.try_shutdown()
    bench.close()


def load(averages) -> str:
    return ", ".join(f"{a:.2f}" for a in averages)


class SnapshotWatch(threading.Thread):
    """Sees the collector's snapshot path at work, every 5 ms: the writer process
    builds each file as a ``.part`` in the pending directory and renames it when
    complete; the database writer stores it into media storage and removes the
    pending file after the commit.  From the first to the last of these is one
    span "during a write"."""

    def __init__(self, directory: Path):
        super().__init__(daemon=True)
        self.directory = directory
        self.names: set[str] = set()
        self.spans: list[list[float]] = []  # [start, end] wall clock
        self.stage = ""  # "building", "storing" or ""
        self.changed = threading.Condition()
        self._halt = threading.Event()

    def run(self) -> None:
        while not self._halt.wait(0.005):
            try:
                names = os.listdir(self.directory)
            except FileNotFoundError:
                names = []
            parts = {n for n in names if n.endswith(".part")}
            done = [n for n in names if n.startswith("snapshot-") and n.endswith(".mcap")]
            self.names |= parts
            stage = "building" if parts else "storing" if done else ""
            now = time.time()
            if stage:
                if self.stage:
                    self.spans[-1][1] = now
                else:
                    self.spans.append([now, now])
            if stage != self.stage:
                with self.changed:
                    self.stage = stage
                    self.changed.notify_all()

    def stop(self) -> None:
        self._halt.set()

    def wait_for(self, stages: tuple[str, ...], timeout: float) -> bool:
        with self.changed:
            return self.changed.wait_for(lambda: self.stage in stages, timeout)

    def since(self, t: float) -> bool:
        """Has a write been going on at some time from ``t`` until now?"""
        return bool(self.spans) and self.spans[-1][1] >= t - 0.005

    def during(self, t: float) -> bool:
        """Was a write going on at wall-clock time ``t``?"""
        return any(start - 0.005 <= t <= end + 0.005 for start, end in self.spans[-50:])

    def overlaps(self, t0: float, t1: float) -> bool:
        return any(start <= t1 and end >= t0 for start, end in self.spans[-50:])

    @property
    def seen(self) -> int:
        return len(self.names)


class Phases:
    """The black box switched on and off every ``seconds`` (``alternate``)."""

    def __init__(self, how: str, seconds: float):
        self.how, self.seconds = how, seconds
        self.enabled = how != "off"
        self.toggles = [(time.time(), self.enabled)]

    def due(self) -> bool:
        return self.how == "alternate" and time.time() - self.toggles[-1][0] >= self.seconds

    def toggle(self) -> None:
        self.enabled = not self.enabled
        self.toggles.append((time.time(), self.enabled))

    def at(self, t: float) -> bool | None:
        """On or off at wall-clock time ``t``; None within 2 s after a toggle
        (subscribing, unsubscribing)."""
        state = None
        for start, enabled in self.toggles:
            if t >= start:
                state = enabled if t >= start + 2.0 or start == self.toggles[0][0] else None
        return state

    def settled(self, t: float) -> bool:
        return self.at(t) is not None


def group(writing: SnapshotWatch, phases: Phases, published: float, done: float) -> str | None:
    """off, idle (on, no write from publishing to the row), write (published while
    a write was going on), mixed (published between writes, one began before the
    row), or None (around a toggle)."""
    enabled = phases.at(published)
    if enabled is None:
        return None
    if not enabled:
        return "off"
    if writing.during(published):
        return "write"
    return "mixed" if writing.overlaps(published, done) else "idle"


def new_groups() -> dict[str, list[float]]:
    return {"off": [], "idle": [], "write": [], "mixed": []}


class Switches:
    """Mode switches, each timed from publishing to its committed master row and
    published at a chosen moment: with the black box on, alternately between
    writes and just as a write begins (the file being built, or the finished
    file about to be stored), balanced by the direction of the switch.  Every
    switch to ITO starts a snapshot whose write begins ``after`` seconds later."""

    def __init__(self, leg, writing: SnapshotWatch, phases: Phases, after: float, gap: float):
        self.leg, self.writing, self.phases, self.after = leg, writing, phases, after
        # Each switch stores the camera frames buffered since the previous one
        # (up to params.image_buffer_size, one per image_buffer_step): published
        # sooner, a switch would carry fewer and be quicker to store.  Every
        # switch waits ``gap`` after the previous one, so all carry a full
        # buffer, as in the field where take-overs are minutes apart; a switch
        # published as a write begins (``after`` > ``gap`` after the switch to
        # ITO) and one published between writes then store the same rows.
        self.gap = gap
        self.last: float = 0.0
        # [published, stored] of each switch (stored: inf while in flight).
        self.spans: list[list[float]] = []
        self.auto = False
        self.ito_at: float | None = None  # last switch to ITO whose write has not begun
        self.delays = new_groups()
        self.counts = {(d, g): 0 for d in (True, False) for g in ("idle", "write")}
        self.stages = {"building": 0, "storing": 0}
        self.by_stage: dict[str, list[float]] = {}

    def next(self, mode, sample) -> None:
        auto = not self.auto
        target = "off"
        if self.phases.enabled:
            target = min(("write", "idle"), key=lambda g: self.counts[(auto, g)])
        if self.ito_at is not None and self.writing.since(self.ito_at):
            self.ito_at = None  # its write began meanwhile
        self._await_gap(sample)
        if target == "write" and not self._await_write(sample):
            target = "idle"
        if target == "idle":
            self._await_quiet(sample)
        stage = self.writing.stage
        kind, delay = self._publish(mode, auto, sample)
        if stage:
            self.stages[stage] += 1
        if kind == "write":
            self.by_stage.setdefault(stage or "ending", []).append(delay)

    def _await_gap(self, sample) -> None:
        while time.time() - self.last < self.gap:
            sample()
            time.sleep(0.01)

    def _await_write(self, sample) -> bool:
        """Until a write begins (False if none is due)."""
        if self.writing.stage:
            return True
        if self.ito_at is None:
            return False
        storing = sum(self.stages.values()) % 2 == 1
        deadline = self.ito_at + self.after + 10.0
        while time.time() < deadline:
            sample()
            if self.writing.wait_for(("storing",) if storing else ("building", "storing"), 0.05):
                self.ito_at = None
                return True
        return False

    def _await_quiet(self, sample) -> None:
        """Until no write goes on or is due within a second, and none ended in
        the last 0.3 s."""
        while True:
            sample()
            now = time.time()
            due = self.ito_at is not None and self.ito_at + self.after - now < 1.0
            recent = self.writing.spans and now - self.writing.spans[-1][1] < 0.3
            if not (self.writing.stage or due or recent):
                return
            if self.ito_at is not None and self.writing.since(self.ito_at):
                self.ito_at = None
            time.sleep(0.01)

    def _publish(self, mode, auto: bool, sample) -> None:
        from std_msgs.msg import Bool

        segments = Segment.objects.masters().filter(leg=self.leg)
        before = segments.count()
        published = self.last = time.time()
        self.spans.append([published, math.inf])
        mode.publish(Bool(data=auto))
        self.auto = auto
        if not auto and self.phases.enabled:
            self.ito_at = published
        while segments.count() == before and time.time() - published < 30:
            sample()
            time.sleep(0.005)
        done = self.spans[-1][1] = time.time()
        kind = group(self.writing, self.phases, published, done)
        if kind is not None:
            self.delays[kind].append(done - published)
            if (auto, kind) in self.counts:
                self.counts[(auto, kind)] += 1
        return kind, done - published


class PoseDelays(threading.Thread):
    """GPS fix stamped (the simulator stamps with its publish time, same clock) →
    its pose row seen by this script, which looks every 20 ms in a thread of its
    own (so up to 20 ms late, whatever the main loop waits for).  Grouped like the
    mode switches, by the moment the fix was published.  Fixes in flight while a
    mode switch was being stored are left out (all groups): a switch is
    published as each write begins, and the fixes that share or wait for its
    transaction (frames, segments) would count its time as the write's."""

    def __init__(self, leg, writing: SnapshotWatch, phases: Phases, switches: "Switches"):
        super().__init__(daemon=True)
        self.leg, self.writing, self.phases, self.switches = leg, writing, phases, switches
        self.last_id = Pose.objects.filter(segment__leg=leg).aggregate(m=Max("id"))["m"] or 0
        self.delays = new_groups()
        self._halt = threading.Event()

    def run(self) -> None:
        try:
            while not self._halt.wait(0.02):
                self.poll()
        finally:
            connection.close()

    def stop(self) -> None:
        self._halt.set()
        self.join()

    def poll(self) -> None:
        rows = list(
            Pose.objects.filter(segment__leg=self.leg, id__gt=self.last_id).values_list(
                "id", "robot_stamp"
            )
        )
        seen = time.time()
        for pk, stamp in rows:
            self.last_id = max(self.last_id, pk)
            if stamp is None:
                continue
            t = stamp.timestamp()
            # In flight (published, not yet seen) while a switch was stored.
            if any(a <= seen and t <= b for a, b in self.switches.spans[-20:]):
                continue
            kind = group(self.writing, self.phases, t, seen)
            if kind is not None:
                self.delays[kind].append(seen - stamp.timestamp())


# Issue 15: "writing a snapshot does not delay mode or pose recording".  Met when
# the delays of messages published during a write are, at the median and at
# p95, within 25 % (+ 20 ms for the 20 ms polling of this script) of those
# published between writes with the black box on, in the same run.
RATIO, SLACK = 1.25, 0.020


def verdict(measures: dict[str, dict[str, list[float]]]) -> str:
    """p50/p95 per group side by side and the target, as figures and a verdict;
    off against idle (which differ by the buffer only) shows the spread of the
    machine at the time."""
    lines = [
        "delays by the black box's state when the message was published (p50 / p95 ms, n):",
        f"  {'':27s} {'off':>17s} {'on, idle':>17s} {'during a write':>17s} "
        f"{'(published idle, write began)':>29s}",
    ]
    met = []
    for label, groups in measures.items():
        cells = []
        for name in ("off", "idle", "write", "mixed"):
            values = groups[name]
            cells.append(
                f"{1000 * percentile(values, 0.5):4.0f} / {1000 * percentile(values, 0.95):4.0f} "
                f"n={len(values):<3d}"
                if values
                else "-"
            )
        lines.append(
            f"  {label:27s} {cells[0]:>17s} {cells[1]:>17s} {cells[2]:>17s} {cells[3]:>29s}"
        )
        idle, write, off = groups["idle"], groups["write"], groups["off"]
        for q, name in ((0.5, "p50"), (0.95, "p95")):
            if len(idle) < 5 or len(write) < 5:
                lines.append(f"    {name}: too few samples")
                met.append(False)
                continue
            w, i = percentile(write, q), percentile(idle, q)
            limit = RATIO * i + SLACK
            ok = w <= limit
            met.append(ok)
            spread_ratio = percentile(off, q) / i if off else math.nan
            lines.append(
                f"    {name}: during a write {1000 * w:.0f} ms, limit {1000 * limit:.0f} ms "
                f"(on-idle {1000 * i:.0f} ms × {RATIO} + {1000 * SLACK:.0f}): write/idle "
                f"{w / i:.2f} [{'ok' if ok else 'over'}]; off/idle {spread_ratio:.2f} "
                f"(the machine's spread)"
            )
    lines.append(
        f"VERDICT writing a snapshot does not delay mode or pose recording "
        f"(during-a-write p50 and p95 ≤ on-idle × {RATIO} + {1000 * SLACK:.0f} ms): "
        f"{'MET' if all(met) else 'NOT MET'}"
    )
    return "\n".join(lines)


def buffer_cost(seconds: int = 60) -> None:
    """CPU of the black box for ``seconds`` of the benchmark robot's traffic (GPS
    100 Hz, TF 50 Hz, mode 2 Hz, 640×480 camera 10 Hz, as JPEG and as raw rgb8),
    fed straight into Blackbox.receive, and the time to write one 30 s window."""
    from rosbridge_app.collector.blackbox import Blackbox

    for camera, frame_bytes in (("JPEG", 60_000), ("raw rgb8", 640 * 480 * 3 + 60)):
        values = {name: spec.default for name, spec in P.SPECS.items()}
        written = []
        box = Blackbox(written.append, values)
        box.directory = Path(tempfile.mkdtemp(prefix="ftt-bench-box-"))
        box.types = {
            "/gps_fix": "sensor_msgs/msg/NavSatFix",
            "/tf": "tf2_msgs/msg/TFMessage",
            "/robot_mode": "std_msgs/msg/Bool",
            "/image": "sensor_msgs/msg/CompressedImage",
        }
        traffic = [("/gps_fix", 100, 96), ("/tf", 50, 140), ("/robot_mode", 2, 8)]
        traffic.append(("/image", 10, frame_bytes))
        # Random bytes: as incompressible as JPEG data.
        per_second = [
            (topic, i * 1_000_000_000 // rate, os.urandom(size))
            for topic, rate, size in traffic
            for i in range(rate)
        ]
        start = time.time_ns() - seconds * 1_000_000_000
        cpu0 = time.process_time()
        for second in range(seconds):
            at = start + second * 1_000_000_000
            for topic, offset, data in per_second:
                box.receive(topic, data, at + offset)
        cpu = time.process_time() - cpu0
        box.after = 0.0
        box.trigger(datetime.fromtimestamp((start + seconds * 10**9) / 1e9, UTC), None, "bench")
        wall0 = time.monotonic()
        box.close()
        write = time.monotonic() - wall0
        mb = sum(p.stat().st_size for p in box.directory.glob("*.mcap")) / 2**20
        shutil.rmtree(box.directory)
        print(
            f"black-box buffer, camera {camera}: {1000 * cpu / seconds:.2f} ms CPU per second "
            f"of traffic ({100 * cpu / seconds:.2f} % of one core), "
            f"{box.buffer.size / 2**20:.0f} MB buffered, {box.buffer.dropped} dropped for size; "
            f"writing the {box.before:.0f} s snapshot ({mb:.0f} MB): {write:.2f} s "
            f"in the writer thread"
        )


def writer_stall(rounds: int = 3) -> None:
    """What writing a 20 s / 12 MB window (the benchmark robot's traffic, JPEG
    camera) does to the other threads of the process that asks for it: a thread
    sleeping 1 ms at a time (as the ROS executor waits for messages) measures how
    late it wakes, while the file is written by a thread of this process (as
    before issue 15's writer process) and by the writer process, alternately, at
    the same load."""
    import threading

    from rosbridge_app.collector.mcap_files import MessageDefinitions, write_mcap
    from rosbridge_app.collector.snapshot_writer import WriterProcess

    traffic = [
        ("/gps_fix", 100, 96),
        ("/tf", 50, 140),
        ("/robot_mode", 2, 8),
        ("/image", 10, 60_000),
    ]
    types = {
        "/gps_fix": "sensor_msgs/msg/NavSatFix",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/robot_mode": "std_msgs/msg/Bool",
        "/image": "sensor_msgs/msg/CompressedImage",
    }
    messages = sorted(
        (second * 10**9 + i * 10**9 // rate, topic, os.urandom(size))
        for second in range(20)
        for topic, rate, size in traffic
        for i in range(rate)
    )
    directory = Path(tempfile.mkdtemp(prefix="ftt-bench-writer-"))
    writer, definitions = WriterProcess(), MessageDefinitions()
    # Started and ready (its type store loaded), as a collector's writer is by
    # the time a window has passed.
    writer.write(directory / "warm.mcap", messages[:10], types, 120.0)

    def stalls(write) -> str:
        late, stop = [], threading.Event()

        def wake() -> None:
            while not stop.is_set():
                t = time.perf_counter()
                time.sleep(0.001)
                late.append(time.perf_counter() - t - 0.001)

        probe = threading.Thread(target=wake)
        probe.start()
        cpu0, wall0 = time.process_time(), time.perf_counter()
        write()
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        stop.set()
        probe.join()
        return (
            f"{wall:.2f} s, {1000 * cpu:.0f} ms CPU here, wake-ups late median "
            f"{1000 * statistics.median(late):.2f} ms, p95 {1000 * percentile(late, 0.95):.1f} ms, "
            f"max {1000 * max(late):.1f} ms"
        )

    for i in range(rounds):
        # The first round's thread also builds the ROS 2 type store, as a
        # collector's first snapshot did; the writer process built it at its start.
        thread = stalls(
            lambda i=i: write_mcap(directory / f"t{i}.mcap", messages, types, definitions)
        )
        child = stalls(lambda i=i: writer.write(directory / f"p{i}.mcap", messages, types, 120.0))
        print(
            f"writing a 12 MB snapshot [load {load(os.getloadavg())}]: in a thread {thread}; "
            f"by the writer process {child}"
        )
    writer.close()
    shutil.rmtree(directory)


def subscription_cost(phase: float = 15.0, phases: int = 4) -> None:
    """What the black box's raw subscriptions add to a process that already
    subscribes the same topics the way the collector's inputs do (deserialized),
    fed by ftt_simulate over DDS at the benchmark rates (GPS 100 Hz, TF 50 Hz,
    JPEG camera 10 Hz, mode 1 Hz): DDS receive, rclpy's take, the callback and
    the buffer.  Phases without and with them alternate; process CPU time, so
    the figure hardly depends on what else the shared machine runs."""
    import functools

    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from rosbridge_app.collector.blackbox import Blackbox
    from rosbridge_app.collector.message_fields import message_class

    values = {name: spec.default for name, spec in P.SPECS.items()}
    box = Blackbox(lambda event: None, values)
    counts: dict[str, int] = {}

    def receive(topic: str, data: bytes) -> None:
        counts[topic] = counts.get(topic, 0) + 1
        box.receive(topic, data)

    topics = {
        "/robot_mode": "std_msgs/msg/Bool",
        "/gps_fix": "sensor_msgs/msg/NavSatFix",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/image_compressed": "sensor_msgs/msg/CompressedImage",
    }
    robot = subprocess.Popen(
        [*MANAGE, "ftt_simulate", "--gps-rate", "100"]
        + ["--tf-rate", "50", "--camera-rate", "10", "--camera-format", "jpeg"]
        + ["--map-size", "10", "--switch-every", "5"]
        + ["--duration", str(phase * phases + 90)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    rclpy.init()
    node = rclpy.create_node("ftt_benchmark_blackbox")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    qos = rclpy.qos.QoSProfile(
        depth=100,
        reliability=rclpy.qos.ReliabilityPolicy.BEST_EFFORT,
        durability=rclpy.qos.DurabilityPolicy.VOLATILE,
    )
    inputs = {"n": 0}

    def collector_input(msg) -> None:
        inputs["n"] += 1

    def spin(duration: float) -> float:
        end = time.monotonic() + duration
        cpu0 = time.process_time()
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.1)
        return time.process_time() - cpu0

    cpu: dict[bool, list[float]] = {False: [], True: []}
    try:
        for topic, typename in topics.items():
            node.create_subscription(message_class(typename), topic, collector_input, qos)
        # Discovery and the simulator's start (seconds on a loaded machine).
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and inputs["n"] < 200:
            executor.spin_once(timeout_sec=0.1)
        raw = []
        for i in range(phases):
            with_box = i % 2 == 1
            if with_box:
                raw = [
                    node.create_subscription(
                        message_class(typename),
                        topic,
                        functools.partial(receive, topic),
                        qos,
                        raw=True,
                    )
                    for topic, typename in topics.items()
                ]
            spin(2.0)  # matching
            counts.clear()
            cpu[with_box].append(spin(phase) / phase)
            received = sum(counts.values()) / phase if with_box else None
            rates = {t: round(n / phase, 1) for t, n in counts.items()} if with_box else None
            for sub in raw:
                node.destroy_subscription(sub)
            raw = []
    finally:
        robot.terminate()
        robot.wait(30)
        node.destroy_node()
        rclpy.try_shutdown()
    without, with_box = (statistics.mean(cpu[k]) for k in (False, True))
    print(
        f"black-box raw subscriptions beside collector-like ones (own process, over DDS "
        f"from ftt_simulate): add {100 * (with_box - without):.1f} % of one core "
        f"({100 * with_box:.1f} % with, {100 * without:.1f} % without, {phases} phases of "
        f"{phase:.0f} s) for {received:.0f} messages/s, per topic {rates}"
    )


def start_bench(label: str, **parameters) -> tuple[Bench, subprocess.Popen]:
    """A throw-away leg and ftt_collect logging into it, once it has beaten."""
    bench = Bench(label, **parameters)
    log = bench.work / "collector.log"
    # collector_bench.MANAGE, not the name imported above: --code replaces it after the import.
    collector = bench.collector(bench.work / "spool.sqlite3", log, manage=collector_bench.MANAGE)
    while not Collector.objects.filter(name=bench.key).exists():
        if collector.poll() is not None:
            raise SystemExit(log.read_text()[-3000:])
        time.sleep(0.2)
    return bench, collector


def lossless_gps(hz: float, count: int, depth: int) -> None:
    """Publish ``count`` NavSatFix at ``hz`` to a collector with thinning off and
    count what arrives and what is stored.  ``depth`` is the publisher's history:
    RELIABLE repeats only what the publisher still keeps, so a fix the
    transport dropped while the machine was busy is lost after ``depth`` more."""
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool

    bench, collector = start_bench(
        "gps",
        **{
            "params.sensor_reliable": True,
            "params.pose_min_distance": 0.0,
            "params.pose_min_period": 0.0,
        },
    )
    key, leg = bench.key, bench.leg
    try:
        rclpy.init()
        node = rclpy.create_node("ftt_gps_benchmark")
        reliable = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
        mode = node.create_publisher(Bool, "robot_mode", 10)
        gps = node.create_publisher(NavSatFix, "gps_fix", reliable)
        while mode.get_subscription_count() == 0 or gps.get_subscription_count() == 0:
            time.sleep(0.05)
        mode.publish(Bool(data=False))
        while not Segment.objects.masters().filter(leg=leg).exists():
            time.sleep(0.05)
        fix = NavSatFix()
        fix.header.frame_id = "gps_link"
        fix.status.status = 0
        fix.altitude = 120.0
        fix.position_covariance = [0.25, 0.0, 0.0, 0.0, 0.25, 0.0, 0.0, 0.0, 1.0]
        fix.position_covariance_type = NavSatFix.COVARIANCE_TYPE_DIAGONAL_KNOWN
        print(f"collector pid {collector.pid}: publishing {count} fixes at {hz:.0f} Hz", flush=True)
        cpu0, _ = proc_sample(collector.pid)
        load0 = os.getloadavg()[0]
        t0 = time.monotonic()
        sent = 0
        # Paced by the clock: a late wake-up publishes the fixes that are due, so
        # the mean rate is the one asked for, with the small bursts a loaded
        # machine gives a real driver too.
        while sent < count:
            due = min(count, int((time.monotonic() - t0) * hz) + 1)
            while sent < due:
                t = time.time()
                fix.header.stamp.sec, fix.header.stamp.nanosec = int(t), int(t % 1 * 1e9)
                fix.latitude = 50.6 + sent * 1e-7
                fix.longitude = 7.1 + (sent % 1000) * 1e-7
                gps.publish(serialize_message(fix))
                sent += 1
            time.sleep(0.0005)
        published_for = time.monotonic() - t0
        stored = 0
        last_change = time.monotonic()
        while stored < sent and time.monotonic() - last_change < 15:
            now_stored = Pose.objects.filter(segment__leg=leg).count()
            if now_stored != stored:
                stored, last_change = now_stored, time.monotonic()
            time.sleep(0.1)
        drained = last_change - t0 - published_for
        cpu1, rss = proc_sample(collector.pid)
        load1 = os.getloadavg()[0]
        collector.send_signal(2)
        collector.wait(60)
        record = Collector.objects.get(name=key)
        received = record.inputs.get("gps_fix", {}).get("count", 0)
        stored = Pose.objects.filter(segment__leg=leg).count()
        print(
            f"database: {connection.vendor} · {os.cpu_count()} cores · load average "
            f"{load0:.2f} → {load1:.2f} (1 min)"
        )
        print(
            f"GPS published: {sent} in {published_for:.1f} s = {sent / published_for:.0f} Hz "
            f"(asked {hz:.0f} Hz), RELIABLE, publisher depth {depth}, thinning off"
        )
        print(
            f"received by the collector: {received} ({100 * received / sent:.2f} %); "
            f"stored: {stored} ({100 * stored / sent:.2f} %), lost {sent - stored}"
        )
        print(f"last row stored {max(0.0, drained):.2f} s after the last fix was published")
        print(
            f"collector CPU while publishing and storing: "
            f"{100 * (cpu1 - cpu0) / (published_for + max(0.0, drained)):.0f} % of one core; "
            f"RSS {rss / 2**20:.0f} MB"
        )
        node.destroy_node()
        rclpy.try_shutdown()
    finally:
        if collector.poll() is None:
            collector.kill()
        bench.close()


def timed_command(record: Collector, parameters: dict | None = None) -> float:
    """Issue a set-parameters command (by default a harmless one), as the GUI
    does, and time it."""
    issued = time.monotonic()
    command = issue_command(
        record,
        CollectorCommand.Kind.SET_PARAMETERS,
        {"parameters": parameters or {"params.send_map_period": 1.0}},
    )
    while not CollectorCommand.objects.filter(pk=command.pk, done__isnull=False).exists():
        if time.monotonic() - issued > 30:
            break
        time.sleep(0.01)
    return time.monotonic() - issued


def spread(label: str, values: list[float]) -> str:
    if not values:
        return f"{label}: no samples"
    return (
        f"{label}: n={len(values)}, median {1000 * statistics.median(values):.0f} ms, "
        f"p95 {1000 * percentile(values, 0.95):.0f} ms, max {1000 * max(values):.0f} ms"
    )


def proc_sample_safe(cpu0, elapsed, samples) -> str:
    return f"{statistics.mean(samples) * elapsed:.0f} CPU-s over {elapsed:.0f} s"


if __name__ == "__main__":
    main()
