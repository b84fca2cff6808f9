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
20 s before; ``after`` is 2 s so that a run has many snapshots.  With
``--snapshot alternate`` (default) it is switched on and off every ``--phase``
seconds through the GUI command path, so the buffer's CPU share is the
difference of the on and off phases of one run, measured under the same load
of the shared machine, with the same switches in both.  The window of a
take-over is written about ``after`` seconds later, when the next switch comes:
a switch whose publish-to-row time overlaps a write (the writer process's
``.part`` file exists in the pending directory) is counted apart, so the
mode-to-row delay is shown during snapshot writes as well as without.  So is
the pose delay: each GPS row the collector stores, from the fix's stamp (the
simulator's publish time) to the moment this script sees the row.  The last
lines put off / on / during a write side by side with the target of issue 15:
writing a snapshot does not delay mode or pose recording ("during a write" no
slower than "on" beyond the spread).

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_throughput.py \
        [--seconds 200] [--snapshot alternate|on|off] [--phase 40] [--camera jpeg|raw] \
        [--map-rate 1] [--ros-domain N] [--latency-only]

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
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

# collector_bench sets the ROS domain and discovery range and sets Django up.
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
    parser.add_argument("--snapshot-after", type=float, default=2.0)
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
    # Mode → row delays and collector CPU per second, by the black box's state.
    delays: dict[str, list[float]] = {"off": [], "on": [], "write": []}
    # The same by the state when the switch was published: a slow switch overlaps
    # a write more often just because it is slow, this grouping does not favour that.
    at_start: dict[str, list[float]] = {"off": [], "on": [], "write": []}
    cpu_by_phase: dict[bool, list[float]] = {True: [], False: []}
    command_delays, cpu_samples, rss_max, pending_max = [], [], 0, 0
    record = Collector.objects.get(name=key)
    cpu0, _ = proc_sample(collector.pid)
    t0 = time.monotonic()
    auto = False
    enabled = args.snapshot != "off"
    phase_start = next_toggle = t0
    if args.snapshot == "alternate":
        next_toggle = t0 + args.phase
    next_switch = t0 + 2.0
    last_cpu, last_t = cpu0, t0
    poses = PoseDelays(leg, writing)
    while robot.poll() is None:
        now = time.monotonic()
        writing.active()
        poses.poll(enabled)
        if args.snapshot == "alternate" and now >= next_toggle:
            enabled = not enabled
            timed_command(record, {"snapshot.enabled": enabled})
            phase_start, next_toggle = now, now + args.phase
        if now >= next_switch and now - t0 < args.seconds - 3:
            auto = not auto
            before = Segment.objects.filter(leg=leg, parent__isnull=True).count()
            published = time.monotonic()
            mode.publish(Bool(data=auto))
            at_publish = during_write = writing.active()
            while Segment.objects.filter(leg=leg, parent__isnull=True).count() == before:
                if time.monotonic() - published > 30:
                    break
                during_write = writing.active() or during_write
                poses.poll(enabled)
                time.sleep(0.005)
            delay = time.monotonic() - published
            delays["write" if during_write else "on" if enabled else "off"].append(delay)
            at_start[group_at(at_publish, enabled)].append(delay)
            next_switch = published + 2.0
            command_delays.append(timed_command(record))
        cpu, rss = proc_sample(collector.pid)
        if now - last_t >= 1.0:
            sample = (cpu - last_cpu) / (now - last_t)
            cpu_samples.append(sample)
            # Subscribing and unsubscribing take up to a tick after a toggle.
            if last_t - phase_start >= 2.0:
                cpu_by_phase[enabled].append(sample)
            last_cpu, last_t = cpu, now
            record = Collector.objects.filter(name=key).first()
            pending_max = max(pending_max, record.pending if record else 0)
        rss_max = max(rss_max, rss)
        time.sleep(0.05)
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
        "master segments": Segment.objects.filter(leg=leg, parent__isnull=True).count(),
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
    print(f"collector RSS: max {rss_max / 2**20:.0f} MB")
    print(f"spool backlog: max {pending_max} records, {spool_left} left after exit")
    for group, label in (
        ("off", "black box off"),
        ("on", "black box on, no snapshot being written"),
        ("write", "while a snapshot was being written"),
    ):
        print(spread(f"mode message → committed master row, {label}", delays[group]))
        print(spread(f"GPS fix stamp → its pose row seen, {label}", poses.delays[group]))
    print(spread("GUI command issued → carried out by the collector", command_delays))
    print("grouped by whether a write overlapped the delay:")
    print(side_by_side({"mode message → master row": delays, "GPS fix → pose row": poses.delays}))
    print("grouped by whether a write was going on when the message was published:")
    print(
        side_by_side({"mode message → master row": at_start, "GPS fix → pose row": poses.at_start})
    )
    node.destroy_node()
    rclpy.try_shutdown()
    bench.close()


def load(averages) -> str:
    return ", ".join(f"{a:.2f}" for a in averages)


class SnapshotWatch:
    """Sees the collector's snapshot writer at work: it writes each snapshot to a
    ``.part`` file in the pending directory and renames it when complete."""

    def __init__(self, directory: Path):
        self.directory = directory
        self.names: set[str] = set()
        self.last_active = 0.0  # wall clock
        self.spans: list[list[float]] = []  # [first, last] time a write was seen

    def active(self) -> bool:
        try:
            parts = {n for n in os.listdir(self.directory) if n.endswith(".part")}
        except FileNotFoundError:
            return False
        self.names |= parts
        if parts:
            now = time.time()
            if self.spans and now - self.spans[-1][1] < 0.25:
                self.spans[-1][1] = now
            else:
                self.spans.append([now, now])
            self.last_active = now
        return bool(parts)

    def during(self, t: float) -> bool:
        """Was a write seen going on at wall-clock time ``t`` (± one poll)?"""
        return any(start - 0.05 <= t <= end + 0.05 for start, end in self.spans)

    @property
    def seen(self) -> int:
        return len(self.names)


class PoseDelays:
    """GPS fix stamped (the simulator stamps with its publish time, same clock) →
    its pose row seen by this script; polled every 50 ms, so up to 50 ms late.
    A row counts as "during a write" when a write was seen between the two."""

    def __init__(self, leg, writing: SnapshotWatch):
        self.leg, self.writing = leg, writing
        self.last_id = Pose.objects.filter(segment__leg=leg).aggregate(m=Max("id"))["m"] or 0
        self.next_poll = 0.0
        self.delays: dict[str, list[float]] = {"off": [], "on": [], "write": []}
        self.at_start: dict[str, list[float]] = {"off": [], "on": [], "write": []}

    def poll(self, enabled: bool) -> None:
        if time.monotonic() < self.next_poll:
            return
        self.next_poll = time.monotonic() + 0.05
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
            at = stamp.timestamp()
            group = "write" if self.writing.last_active >= at else "on" if enabled else "off"
            self.delays[group].append(seen - at)
            self.at_start[group_at(self.writing.during(at), enabled)].append(seen - at)


def group_at(writing: bool, enabled: bool) -> str:
    return "write" if writing else "on" if enabled else "off"


def side_by_side(measures: dict[str, dict[str, list[float]]]) -> str:
    """Medians and p95 of off / on / during a write, and the target of issue 15."""
    lines = [
        "writing a snapshot must not delay mode or pose recording "
        "(target: during a write no slower than on, beyond the spread):",
        f"  {'':28s} {'off':>16s} {'on':>16s} {'during a write':>16s}   write/on (median)",
    ]
    for label, groups in measures.items():
        cells = []
        for group in ("off", "on", "write"):
            values = groups[group]
            cells.append(
                f"{1000 * statistics.median(values):5.0f}/{1000 * percentile(values, 0.95):5.0f}"
                f" n={len(values):<3d}"
                if values
                else f"{'-':>16s}"
            )
        on, write = groups["on"], groups["write"]
        ratio = statistics.median(write) / statistics.median(on) if on and write else math.nan
        lines.append(f"  {label:28s} {cells[0]:>16s} {cells[1]:>16s} {cells[2]:>16s}   {ratio:.2f}")
    lines.append("  (median/p95 in ms)")
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

    from rosbridge_app.collector.blackbox import MessageDefinitions, WriterProcess, write_mcap

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

    from rosbridge_app.collector.blackbox import Blackbox, message_class

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
    collector = bench.collector(bench.work / "spool.sqlite3", log)
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
        while not Segment.objects.filter(leg=leg, parent__isnull=True).exists():
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
