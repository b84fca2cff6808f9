"""How long ftt_collect takes from its start to the first stored message, and where it goes.

A robot in this process publishes a GPS fix at 10 Hz and the mode at 2 Hz
before the collector starts. Each run starts ``manage.py ftt_collect`` with an
empty spool and ``--start-logging`` and waits for the first stored pose; the
collector logs where its start-up went (``start-up N s: ...``: Python, Django
and the command loaded, rclpy.init, node, first message, first record
stored), which is printed per run. Then the parts alone, each in a fresh
interpreter: Python (with the ROS wheels' re-exec), Django set-up, rclpy.

    [FTT_DATABASE_URL=postgis://...] .venv/bin/python benchmarks/collector_startup.py [--runs 3]

Target (issue 16): 3 s on an idle machine. The load average is printed with
every figure, because the machine is shared. Uses a throw-away vehicle and
test event and deletes them afterwards; its own ROS domain and loopback
discovery.
"""

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

from collector_bench import Bench, load
from django.db import connection

from rosbridge_app.models import Collector
from telemetry.models import Pose

PARTS = {
    "Python (and the ROS wheels' re-exec)": "pass",
    "Django set-up": "import django; django.setup()",
    "import rclpy, rclpy.init": "import rclpy; rclpy.init(); rclpy.shutdown()",
}


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


class Robot(threading.Thread):
    def __init__(self):
        import rclpy
        from sensor_msgs.msg import NavSatFix
        from std_msgs.msg import Bool

        super().__init__(daemon=True)
        rclpy.init()
        self.node = rclpy.create_node("ftt_startup_robot")
        self.fix = self.node.create_publisher(NavSatFix, "gps_fix", 50)
        self.mode = self.node.create_publisher(Bool, "robot_mode", 10)
        self.NavSatFix, self.Bool = NavSatFix, Bool
        self.halt = threading.Event()

    def run(self):
        i = 0
        while not self.halt.is_set():
            i += 1
            fix = self.NavSatFix(latitude=50.0 + i * 1e-6, longitude=7.0)
            fix.status.status = 0  # a fix (the message's default is "unknown")
            fix.header.stamp = self.node.get_clock().now().to_msg()
            self.fix.publish(fix)
            if i % 5 == 0:
                self.mode.publish(self.Bool(data=True))
            time.sleep(0.1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    bench = Bench("startup", **{"params.pose_min_distance": 0.0})
    leg, work, env = bench.leg, bench.work, bench.env
    robot = Robot()
    robot.start()
    print(f"database: {connection.vendor} · {os.cpu_count()} cores")
    totals, cpus = [], []
    try:
        for run in range(1, args.runs + 1):
            log = work / f"collector-{run}.log"
            before = Pose.objects.filter(segment__leg=leg).count()
            started = time.monotonic()
            collector = bench.collector(work / f"spool-{run}.sqlite3", log)
            while Pose.objects.filter(segment__leg=leg).count() == before:
                if time.monotonic() - started > 60 or collector.poll() is not None:
                    break
                time.sleep(0.05)
            seen = time.monotonic() - started
            cpu = cpu_seconds(collector.pid)
            totals.append(seen)
            cpus.append(cpu)
            collector.send_signal(2)
            collector.wait(60)
            output = log.read_text(errors="replace")
            if seen > 60:
                record = Collector.objects.filter(name=bench.key).first()
                print(output[-3000:], record and record.inputs, record and record.state)
            timeline = re.search(r"start-up [^\n]*", output)
            print(
                f"run {run}: first stored pose seen after {seen:.2f} s, the collector had "
                f"used {cpu:.2f} s of CPU by then ({load()})"
            )
            print(f"  collector: {timeline.group(0) if timeline else 'no start-up line'}")
    finally:
        robot.halt.set()
        robot.join(2)
    print(
        f"start to first stored message: median {statistics.median(totals):.2f} s, "
        f"min {min(totals):.2f} s over {len(totals)} runs; CPU used by then: median "
        f"{statistics.median(cpus):.2f} s, what an idle machine would need at least ({load()})"
    )
    for label, code in PARTS.items():
        times, used = [], []
        for _ in range(3):
            t, before = time.monotonic(), children_cpu()
            subprocess.run([sys.executable, "-c", code], env=env, check=True, capture_output=True)
            times.append(time.monotonic() - t)
            used.append(children_cpu() - before)
        print(
            f"  alone: {label}: median {statistics.median(times):.2f} s, "
            f"CPU {statistics.median(used):.2f} s ({load()})"
        )
    bench.close()


if __name__ == "__main__":
    main()
