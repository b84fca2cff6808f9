"""What ftt_collect sustains on this machine, into the configured database.

A simulated robot (ftt_simulate, its own process) publishes GPS at 100 Hz, TF
at 50 Hz, a 640×480 rgb8 camera at 10 Hz and a 2000×2000 occupancy grid that
changes every second; this script publishes a mode switch every 2 s and
times each one from publish to its committed master row.  The collector runs
as its own process with the shipped parameters (map stored at most once a
second).  Prints what was published and received, rows written, the
collector's CPU and memory, the spool backlog, the mode-to-row delay, and how
long a GUI command (set parameters, issued through the database between two
mode switches) takes to be carried out while the robot is this busy.

The black box buffers the mode, GPS, TF and raw camera topics (9 MB/s) and
writes a 6 s snapshot at every switch to ITO; ``--snapshot off`` runs without
it, so the buffer's CPU cost is the difference of the two runs' collector CPU.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_throughput.py \
        [--seconds 60] [--snapshot on|off]

Uses a throw-away vehicle and test event in that database and deletes them
afterwards.  Sets its own ROS domain (40-59) and loopback discovery.
"""

import argparse
import os
import re
import shutil
import statistics
import subprocess
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

from collector_bench import Bench, load
from django.db import connection

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
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument(
        "--reliable",
        action="store_true",
        help="Subscribe GPS and camera RELIABLE (params.sensor_reliable).",
    )
    parser.add_argument("--snapshot", choices=("on", "off"), default="on")
    parser.add_argument("--snapshot-after", type=float, default=1.0)
    parser.add_argument(
        "--buffer-only",
        action="store_true",
        help="Only the black box's own cost, in this process, without ROS or a database.",
    )
    args = parser.parse_args()
    buffer_cost()
    if args.buffer_only:
        return

    import rclpy
    from std_msgs.msg import Bool

    bench = Bench(
        "throughput",
        **{
            "params.send_map_period": 1.0,
            "params.sensor_reliable": args.reliable,
            "snapshot.enabled": args.snapshot == "on",
            # The simulator's camera is raw rgb8 (the default list has the compressed one).
            "snapshot.topics": "robot_mode, gps_fix, /tf, /tf_static, image",
            # Mode switches come every 2 s: short windows keep the disk use of a run small.
            "snapshot.before": 5.0,
            "snapshot.after": args.snapshot_after,
        },
    )
    key, leg = bench.key, bench.leg
    collector = bench.collector(bench.work / "spool.sqlite3", bench.work / "collector.log")
    while not Collector.objects.filter(name=key).exists():
        time.sleep(0.2)
    robot = bench.robot(args.seconds, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    rclpy.init()
    node = rclpy.create_node("ftt_benchmark")
    mode = node.create_publisher(Bool, "robot_mode", 10)
    while mode.get_subscription_count() == 0:
        time.sleep(0.05)
    delays, command_delays, cpu_samples, rss_max, pending_max = [], [], [], 0, 0
    record = Collector.objects.get(name=key)
    cpu0, _ = proc_sample(collector.pid)
    t0 = time.monotonic()
    auto = False
    next_switch = t0 + 2.0
    last_cpu, last_t = cpu0, t0
    while robot.poll() is None:
        now = time.monotonic()
        if now >= next_switch and now - t0 < args.seconds - 3:
            auto = not auto
            before = Segment.objects.filter(leg=leg, parent__isnull=True).count()
            published = time.monotonic()
            mode.publish(Bool(data=auto))
            while Segment.objects.filter(leg=leg, parent__isnull=True).count() == before:
                if time.monotonic() - published > 30:
                    break
                time.sleep(0.005)
            delays.append(time.monotonic() - published)
            next_switch = published + 2.0
            command_delays.append(timed_command(record))
        cpu, rss = proc_sample(collector.pid)
        if now - last_t >= 1.0:
            cpu_samples.append((cpu - last_cpu) / (now - last_t))
            last_cpu, last_t = cpu, now
            record = Collector.objects.filter(name=key).first()
            pending_max = max(pending_max, record.pending if record else 0)
        rss_max = max(rss_max, rss)
        time.sleep(0.05)
    elapsed = time.monotonic() - t0
    published = robot.stdout.read()
    collector.send_signal(2)
    collector.wait(60)
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
        f"sensor QoS {qos} · {load()}"
    )
    print(f"published by the robot: {published.strip().splitlines()[-1]}")
    print(f"received by the collector: {counts}")
    match = re.search(r"\{.*\}", published)
    if match:
        sent = eval(match.group(0), {})  # our own simulator's printed dict
        for name, topic in (("gps", "gps_fix"), ("tf", "tf"), ("image", "image"), ("map", "map")):
            got = counts.get(topic, 0)
            print(
                f"  {name:5s}: {got}/{sent[name]} received ({100 * got / max(1, sent[name]):.1f} %)"
            )
    print(f"rows written: {rows}")
    print(
        f"black box {args.snapshot}: {rows['snapshots']} snapshots, {snapshot_mb:.0f} MB, "
        f"messages {in_snapshots}"
    )
    print(
        f"collector CPU: mean {100 * statistics.mean(cpu_samples):.0f} % of one core, "
        f"max {100 * max(cpu_samples):.0f} %; total {cpu_total}"
    )
    print(f"collector RSS: max {rss_max / 2**20:.0f} MB")
    print(f"spool backlog: max {pending_max} records, {spool_left} left after exit")
    print(spread("mode message → committed master row", delays))
    print(spread("GUI command issued → carried out by the collector", command_delays))
    node.destroy_node()
    rclpy.try_shutdown()
    bench.close()


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


def timed_command(record: Collector) -> float:
    """Issue a harmless set-parameters command, as the GUI does, and time it."""
    issued = time.monotonic()
    command = issue_command(
        record,
        CollectorCommand.Kind.SET_PARAMETERS,
        {"parameters": {"params.send_map_period": 1.0}},
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
