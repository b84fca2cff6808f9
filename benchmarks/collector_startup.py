"""How long ftt_collect takes from its start to its subscriptions and the first stored message.

A robot in this process publishes a GPS fix at 10 Hz and the mode at 2 Hz
before the collector starts. Each run starts ``manage.py ftt_collect`` with an
empty spool and ``--start-logging`` and waits for the first stored pose; the
collector logs where its start-up went (``start-up N s: ...``: Python, Django
and the command loaded, rclpy.init, node, subscriptions and services, first
message, first record stored), which is printed per run. Then the parts alone,
each in a fresh interpreter: Python (with the ROS wheels' re-exec), Django
set-up, rclpy, and ``ftt_collect`` up to its first subscription (the process
ends there).

With ``--against DIR`` the runs alternate between this checkout and the one in
DIR (same virtualenv, same database; e.g. ``git worktree add --detach
/tmp/ftt-main main``), and each figure is printed for both, side by side:

    [FTT_DATABASE_URL=postgis://...] .venv/bin/python benchmarks/collector_startup.py \
        [--runs 3] [--against /tmp/ftt-main]

Target (issue 41): 1.5 s from the process's start to its subscriptions on an
idle machine, with the project's bytecode compiled (as after a first start;
the benchmark compiles both checkouts). The load average is printed with every figure, because the
machine is shared. Uses a throw-away vehicle and test event and deletes them
afterwards; its own ROS domain and loopback discovery.
"""

import argparse
import compileall
import os
import re
import resource
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

from collector_bench import ROOT, Bench, load
from django.apps import apps
from django.db import connection

from rosbridge_app.models import Collector
from telemetry.models import Pose

# ftt_collect (the arguments after the code) until its first subscription: the
# process ends there, before discovery and the database.
UNTIL_SUBSCRIBED = (
    "import os, runpy, sys, rclpy.node\n"
    "rclpy.node.Node.create_subscription = lambda *args, **kwargs: os._exit(0)\n"
    "sys.argv = ['manage.py', *sys.argv[1:]]\n"
    "runpy.run_path('manage.py', run_name='__main__')\n"
)
PARTS = {
    "Python (and the ROS wheels' re-exec)": ["pass"],
    "Django set-up": ["import django; django.setup()"],
    "import rclpy, rclpy.init": ["import rclpy; rclpy.init(); rclpy.shutdown()"],
    "ftt_collect to its first subscription": [UNTIL_SUBSCRIBED, "ftt_collect"],
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


# The collector's start-up phases up to and including its subscriptions.
TO_SUBSCRIPTIONS = (
    "Python, Django and the command loaded",
    "rclpy.init",
    "node, subscriptions and services",
)


def phases(line: str) -> dict[str, float]:
    """The collector's ``start-up N s: label +t s, label +t s, ...`` (labels hold commas)."""
    steps = line.split(" s: ", 1)[-1]
    return {label: float(t) for label, t in re.findall(r"(.+?) \+([\d.]+) s(?:, |$)", steps)}


def median(values: list[float]) -> str:
    return f"{statistics.median(values):.2f} s" if values else "-"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument(
        "--against",
        type=Path,
        help="another checkout (same virtualenv): its collector is measured beside this one",
    )
    args = parser.parse_args()
    checkouts = {"this checkout": ROOT}
    if args.against:
        checkouts[f"against {args.against}"] = args.against.resolve()
    bench = Bench("startup", **{"params.pose_min_distance": 0.0})
    leg, work, env = bench.leg, bench.work, bench.env
    robot = Robot()
    robot.start()
    print(f"database: {connection.vendor} · {os.cpu_count()} cores")
    for name, root in checkouts.items():
        print(f"{name}: {root} ({git_head(root)})")
        # As after the collector's first start: each module's bytecode cached
        # (PYTHONDONTWRITEBYTECODE would otherwise compile the project every run).
        for package in own_apps():
            compileall.compile_dir(root / package, quiet=1)
    figures = {name: {"subscribed": [], "stored": [], "cpu": []} for name in checkouts}
    try:
        for run in range(1, args.runs + 1):
            # Alternated, so that both see the same load.
            for name, root in checkouts.items():
                measure(bench, leg, work, run, name, root, figures[name])
    finally:
        robot.halt.set()
        robot.join(2)
    print(f"medians over {args.runs} runs ({load()}):")
    for name, got in figures.items():
        print(
            f"  {name}: start to subscriptions {median(got['subscribed'])}, to the first "
            f"stored message {median(got['stored'])} (min {min(got['stored']):.2f} s); CPU "
            f"used by then {median(got['cpu'])}, what an idle machine would need at least"
        )
    collect = ["--params-file", str(bench.params), "--spool", str(work / "spool-parts.sqlite3")]
    for label, (code, *command) in PARTS.items():
        times = {name: [] for name in checkouts}
        used = {name: [] for name in checkouts}
        for _ in range(args.runs):
            for name, root in checkouts.items():
                t, before = time.monotonic(), children_cpu()
                subprocess.run(
                    [sys.executable, "-c", code, *command, *(collect if command else [])],
                    cwd=root,
                    env=env,
                    check=True,
                    capture_output=True,
                )
                times[name].append(time.monotonic() - t)
                used[name].append(children_cpu() - before)
        for name in checkouts:
            print(
                f"  alone: {label}, {name}: median {median(times[name])}, "
                f"CPU {median(used[name])} ({load()})"
            )
    bench.close()


def own_apps() -> list[str]:
    """FTT's own apps (the installed ones in this checkout), by package name."""
    return [app.name for app in apps.get_app_configs() if Path(app.path).is_relative_to(ROOT)]


def git_head(root: Path) -> str:
    done = subprocess.run(
        ["git", "-C", str(root), "log", "-1", "--format=%h %s"], capture_output=True, text=True
    )
    return done.stdout.strip()[:72] or "not a git checkout"


def measure(bench: Bench, leg, work: Path, run: int, name: str, root: Path, got: dict) -> None:
    tag = f"{run}-{len(got['stored'])}-{abs(hash(name)) % 1000}"
    log = work / f"collector-{tag}.log"
    before = Pose.objects.filter(segment__leg=leg).count()
    started = time.monotonic()
    collector = bench.collector(
        work / f"spool-{tag}.sqlite3", log, manage=[sys.executable, str(root / "manage.py")]
    )
    while Pose.objects.filter(segment__leg=leg).count() == before:
        if time.monotonic() - started > 60 or collector.poll() is not None:
            break
        time.sleep(0.05)
    seen = time.monotonic() - started
    cpu = cpu_seconds(collector.pid)
    collector.send_signal(2)
    collector.wait(60)
    output = log.read_text(errors="replace")
    if seen > 60:
        record = Collector.objects.filter(name=bench.key).first()
        print(output[-3000:], record and record.inputs, record and record.state)
    timeline = re.search(r"start-up [^\n]*", output)
    steps = phases(timeline.group(0)) if timeline else {}
    got["stored"].append(seen)
    got["cpu"].append(cpu)
    if all(label in steps for label in TO_SUBSCRIPTIONS):
        got["subscribed"].append(sum(steps[label] for label in TO_SUBSCRIPTIONS))
    print(
        f"run {run}, {name}: first stored pose seen after {seen:.2f} s, the collector had "
        f"used {cpu:.2f} s of CPU by then ({load()})"
    )
    print(f"  collector: {timeline.group(0) if timeline else 'no start-up line'}")


if __name__ == "__main__":
    main()
