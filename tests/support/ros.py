"""Helpers for tests that run real ROS 2 processes (marker ``ros``).

Every run uses its own ROS domain (scripts/test.sh picks it, and each xdist
worker takes the next one: tests/support/workers.py) and loopback-only
discovery, so parallel runs on one machine never see each other's topics.
"""

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.support.workers import assign_worker_resources

ROOT = Path(__file__).resolve().parents[2]
# This worker's own; the root conftest's pytest_configure may not have run yet.
assign_worker_resources()
DOMAIN_ID = int(os.environ["FTT_ROS_DOMAIN_ID"])

# Set for this process before rclpy loads (in-process publishers) and inherited
# by the processes the tests start.
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN_ID)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("RMW_IMPLEMENTATION", None)
os.environ.pop("ROS_LOCALHOST_ONLY", None)


def ros_available() -> bool:
    try:
        import industrial_msgs.msg  # noqa: F401
        import rclpy  # noqa: F401
        import tf2_msgs.msg  # noqa: F401
    except ImportError:
        return False
    return True


requires_ros = pytest.mark.skipif(
    not ros_available(), reason="rclpy, tf2_msgs or industrial_msgs missing (scripts/setup.sh)"
)


def wait_for(predicate, timeout: float = 15.0, interval: float = 0.1, what: str = "condition"):
    end = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(interval)


def database_url(settings_dict: dict) -> str:
    s = settings_dict
    return (
        f"postgis://{s['USER']}:{s['PASSWORD']}@{s['HOST'] or '127.0.0.1'}:"
        f"{s['PORT'] or 5432}/{s['NAME']}"
    )


class Process:
    """A manage.py command in its own process, output kept in a file."""

    def __init__(self, args: list[str], log: Path, env: dict):
        self.log = log
        self.args = args
        self._file = open(log, "ab")  # noqa: SIM115 - closed in stop()
        self.popen = subprocess.Popen(
            [sys.executable, str(ROOT / "manage.py"), *args],
            cwd=ROOT,
            env=env,
            stdout=self._file,
            stderr=subprocess.STDOUT,
        )

    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def alive(self) -> bool:
        return self.popen.poll() is None

    def stop(self, sig=signal.SIGTERM, timeout: float = 20.0) -> int | None:
        if self.popen.poll() is None:
            self.popen.send_signal(sig)
            try:
                self.popen.wait(timeout)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait(5)
        self._file.close()
        return self.popen.returncode


class Processes:
    def __init__(self, tmp_path: Path, env: dict):
        self.tmp_path, self.env, self.started = tmp_path, env, []

    def start(self, *args: str, name: str = "proc", env: dict | None = None) -> Process:
        p = Process(list(args), self.tmp_path / f"{name}.log", {**self.env, **(env or {})})
        self.started.append(p)
        return p

    def stop_all(self) -> None:
        for p in reversed(self.started):
            p.stop(signal.SIGTERM, timeout=15)
        fastdds = Path(sys.executable).parent / "fastdds"
        if fastdds.exists():
            # A SIGKILLed participant leaves shared-memory segments behind.
            subprocess.run([str(fastdds), "shm", "clean"], capture_output=True, timeout=30)


class RosClient:
    """An rclpy node in the test process: publishers, service and parameter calls."""

    def __init__(self, name: str = "ftt_test_client"):
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.rclpy = rclpy
        self.context = Context()
        rclpy.init(context=self.context, domain_id=DOMAIN_ID)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        while not self._stop.is_set() and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:
                return

    def close(self):
        self._stop.set()
        self._thread.join(5)
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)

    def publisher(self, msg_type, topic: str, qos=10):
        return self.node.create_publisher(msg_type, topic, qos)

    def wait_subscribed(self, publisher, timeout: float = 15.0):
        wait_for(
            lambda: publisher.get_subscription_count() > 0,
            timeout,
            what=f"a subscriber on {publisher.topic_name}",
        )

    def call(self, srv_type, name: str, request, timeout: float = 10.0):
        client = self.node.create_client(srv_type, name)
        try:
            assert client.wait_for_service(timeout_sec=timeout), f"no service {name}"
            future = client.call_async(request)
            return wait_for(
                lambda: future.result() if future.done() else None,
                timeout,
                interval=0.02,
                what=f"the answer of {name}",
            )
        finally:
            self.node.destroy_client(client)

    def set_logging(self, on: bool):
        from std_srvs.srv import SetBool

        return self.call(SetBool, "/set_ftt_logging", SetBool.Request(data=on))

    def trigger(self, name: str):
        from std_srvs.srv import Trigger

        return self.call(Trigger, name, Trigger.Request())

    def parameters(self, node_name: str = "ftt_collector"):
        from rclpy.parameter_client import AsyncParameterClient

        return AsyncParameterClient(self.node, node_name)

    def await_future(self, future, timeout: float = 10.0):
        return wait_for(
            lambda: future.result() if future.done() else None,
            timeout,
            interval=0.02,
            what="a ROS future",
        )


def copy_default_params(tmp_path: Path, **overrides) -> Path:
    from rosbridge_app.collector import params

    values = params.read_file(params.DEFAULT_FILE)
    values.update(overrides)
    path = tmp_path / "ftt_collect.yaml"
    params.write_file(path, values)
    return path


def fastdds_clean():
    fastdds = shutil.which("fastdds", path=str(Path(sys.executable).parent))
    if fastdds:
        subprocess.run([fastdds, "shm", "clean"], capture_output=True, timeout=30)
