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

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/collector_throughput.py \
        [--seconds 60]

Uses a throw-away vehicle and test event in that database and deletes them
afterwards.  Sets its own ROS domain (40-59) and loopback discovery.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")
os.environ["ROS_DOMAIN_ID"] = str(40 + os.getpid() % 20)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("RMW_IMPLEMENTATION", None)

import django  # noqa: E402

django.setup()

from django.db import connection  # noqa: E402

from events.models import Segment, Vehicle  # noqa: E402
from events.services import deletion, logs  # noqa: E402
from rosbridge_app.collector import params as P  # noqa: E402
from rosbridge_app.models import Collector, CollectorCommand  # noqa: E402
from rosbridge_app.services.collectors import issue_command  # noqa: E402
from telemetry.models import Image, LocalPose, MapImage, Pose  # noqa: E402

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
    args = parser.parse_args()

    import rclpy
    from std_msgs.msg import Bool

    key = f"bench-{os.getpid()}"
    vehicle = Vehicle.objects.create(key=key, short_description="collector benchmark")
    event = logs.create_test_event(location="collector benchmark")
    leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
    work = Path(tempfile.mkdtemp(prefix="ftt-bench-"))
    values = P.read_file(P.DEFAULT_FILE)
    values.update(
        {"vehicle": key, "params.send_map_period": 1.0, "params.sensor_reliable": args.reliable}
    )
    P.write_file(work / "params.yaml", values)
    env = {
        **os.environ,
        "PYTHONUNBUFFERED": "1",
        "FTT_DATA_DIR": str(work),
        "FTT_MEDIA_ROOT": str(work / "media"),
    }
    manage = [sys.executable, str(ROOT / "manage.py")]
    collector = subprocess.Popen(
        [
            *manage,
            "ftt_collect",
            "--params-file",
            str(work / "params.yaml"),
            "--name",
            key,
            "--spool",
            str(work / "spool.sqlite3"),
            "--start-logging",
        ],
        env=env,
        stdout=open(work / "collector.log", "wb"),
        stderr=subprocess.STDOUT,
    )
    while not Collector.objects.filter(name=key).exists():
        time.sleep(0.2)
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
            "--map-size",
            "2000",
            "--map-rate",
            "1",
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
    }
    spool_left = record.pending
    qos = "RELIABLE" if args.reliable else "BEST_EFFORT"
    print(
        f"database: {connection.vendor} · {os.cpu_count()} cores · {elapsed:.0f} s run · "
        f"sensor QoS {qos}"
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
        f"collector CPU: mean {100 * statistics.mean(cpu_samples):.0f} % of one core, "
        f"max {100 * max(cpu_samples):.0f} %; total {cpu_total}"
    )
    print(f"collector RSS: max {rss_max / 2**20:.0f} MB")
    print(f"spool backlog: max {pending_max} records, {spool_left} left after exit")
    print(spread("mode message → committed master row", delays))
    print(spread("GUI command issued → carried out by the collector", command_delays))
    node.destroy_node()
    rclpy.try_shutdown()
    deletion.delete(event)
    Collector.objects.filter(name=key).delete()
    deletion.delete(vehicle)


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
