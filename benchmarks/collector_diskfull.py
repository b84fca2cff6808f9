"""The ``diskfull`` drill of benchmarks/collector_endurance.py (issue 32): see
its docstring; the drill itself is tests/support/diskfull.py, which its test
runs too."""

import os
import subprocess
import threading
import time
from urllib.parse import urlsplit, urlunsplit

from collector_bench import MANAGE, load
from django.db import connection

from tests.support import diskfull


def disk_full(bench, minutes: float) -> None:
    import rclpy

    from rosbridge_app.collector import params as P

    values = P.read_file(bench.params)
    P.write_file(bench.params, {**values, "spool.disk_headroom_mb": 1})
    url = urlsplit(os.environ["FTT_DATABASE_URL"])
    relay = diskfull.Relay((url.hostname or "127.0.0.1", url.port or 5432))
    relay.start()
    netloc = f"{url.username}:{url.password}@127.0.0.1:{relay.port}"
    env = {"FTT_DATABASE_URL": urlunsplit(url._replace(netloc=netloc))}
    log = bench.work / "collector.log"
    rclpy.init()
    node = rclpy.create_node("ftt_diskfull")
    listener = diskfull.Listener(node)
    spinner = threading.Thread(target=rclpy.spin, args=(node,), daemon=True)
    spinner.start()
    with diskfull.small_filesystem(bench.work / "disk", 6) as disk:
        collector = bench.collector(disk / "spool.sqlite3", log, env)
        robot = subprocess.Popen(
            [*MANAGE, "ftt_simulate", *diskfull.ROBOT, "--switch-every", "10"],
            env=bench.env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.STDOUT,
        )
        print(f"database: {connection.vendor} · {os.cpu_count()} cores · {load()}")
        try:
            figures = diskfull.run(
                relay=relay,
                leg=bench.leg,
                name=bench.key,
                log=log,
                listener=listener,
                full_seconds=minutes * 60,
                after_seconds=10,
                alive=lambda: collector.poll() is None,
            )
        finally:
            robot.terminate()
            robot.wait(30)
            collector.send_signal(2)
            stopping = time.monotonic()
            collector.wait(120)
            stopping = time.monotonic() - stopping
    text = log.read_text(errors="replace")
    print(f"figures ({load()}):")
    for key, value in figures.items():
        print(f"  {key}: {value:.2f}" if isinstance(value, float) else f"  {key}: {value}")
    print(f"  the collector stopped {stopping:.1f} s after SIGINT; it logged 'robot disk full (' ")
    print(f"  {text.count('robot disk full (')} times and {text.count('Traceback')} tracebacks")
