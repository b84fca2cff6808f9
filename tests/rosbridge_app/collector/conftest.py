"""Fixtures for the collector tests that start real processes (marker ``ros``)."""

import hashlib
import importlib
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from events.models import Segment, Vehicle
from events.services import logs
from rosbridge_app.models import Collector
from tests.support.ros import (
    ROOT,
    Processes,
    RosClient,
    copy_default_params,
    database_url,
    wait_for,
)

VEHICLE = "ros-bot"
ROBOT_MSGS = Path(__file__).parent / "robot_msgs" / "ftt_robot_msgs"


@pytest.fixture
def ros_env(transactional_db, tmp_path, settings):
    """Environment for collector processes, pointing at this test's database."""
    from django.db import connection

    if connection.vendor != "postgresql":
        pytest.skip("collector processes need a database server (FTT_DATABASE_URL=postgis://)")
    media = tmp_path / "media"
    settings.MEDIA_ROOT = media
    env = dict(os.environ)
    env.update(
        FTT_DATABASE_URL=database_url(connection.settings_dict),
        FTT_DATA_DIR=str(tmp_path / "data"),
        FTT_MEDIA_ROOT=str(media),
        FTT_LOG_LEVEL="INFO",
        PYTHONUNBUFFERED="1",
    )
    return env


@pytest.fixture
def procs(ros_env, tmp_path):
    processes = Processes(tmp_path, ros_env)
    yield processes
    processes.stop_all()


@pytest.fixture
def ros():
    client = RosClient()
    yield client
    client.close()


@pytest.fixture
def robot_leg(transactional_db):
    # A transactional test before this one may have flushed the seeded
    # catalogues (segment types, reasons); the seeding is idempotent.
    from django.apps import apps

    importlib.import_module("events.migrations.0002_seed_catalogues_and_roles").seed(apps, None)
    vehicle = Vehicle.objects.create(key=VEHICLE, short_description="Test robot")
    event = logs.create_test_event(location="Test field")
    return logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))


@pytest.fixture
def start_collector(procs, tmp_path, robot_leg):
    """start_collector(name, params={...}, args=[...]) → the running process, once it
    has beaten (so its subscriptions exist)."""

    def start(name="collector", params=None, args=(), env=None, wait=True):
        params_file = tmp_path / f"{name}.yaml"
        if not params_file.exists():
            copy_default_params(tmp_path, vehicle=VEHICLE, **(params or {})).rename(params_file)
        p = procs.start(
            "ftt_collect",
            "--params-file",
            str(params_file),
            "--name",
            name,
            "--spool",
            str(tmp_path / f"{name}.spool.sqlite3"),
            *args,
            name=name,
            env=env,
        )
        p.params_file = params_file
        if wait:
            pid = p.popen.pid
            wait_for(
                lambda: (
                    not p.alive()
                    or Collector.objects.filter(name=name, pid=pid, stopped=None).exists()
                ),
                40,
                what=f"the first heartbeat of {name}",
            )
            assert p.alive(), p.output()
        return p

    return start


def logging_robot(ros, start_collector, leg, depth: int, params=None, auto: bool = False):
    """A collector logging with thinning off and the robot's reliable GPS
    publisher (keeping ``depth`` fixes, so the reliable protocol can repeat
    what the transport dropped): (collector, fix publisher, the master its
    first mode opened)."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool

    collector = start_collector(
        params={
            "params.sensor_reliable": True,
            "params.pose_min_distance": 0.0,
            "params.pose_min_period": 0.0,
            **(params or {}),
        },
        args=["--start-logging"],
    )
    mode = ros.publisher(Bool, "/robot_mode")
    fixes = ros.publisher(
        NavSatFix, "/gps_fix", QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
    )
    for publisher in (mode, fixes):
        ros.wait_subscribed(publisher)
    mode.publish(Bool(data=auto))
    master = wait_for(
        lambda: Segment.objects.filter(leg=leg, parent__isnull=True).first(),
        what="the first master",
    )
    return collector, fixes, master


# What builds a team's interfaces at setup: the hook and the scripts it calls.
BUILD_SCRIPTS = [
    "scripts/setup.d/50-ros-interfaces.sh",
    "scripts/build_interfaces.sh",
    "scripts/ros_package.py",
]


@pytest.fixture(scope="session")
def robot_interfaces() -> dict:
    """Environment of processes that use ftt_robot_msgs, built once per
    definition set and build scripts (2-3 min) by setup's own step, as
    FTT_ROS_INTERFACES=ftt_robot_msgs (relative to where it runs) into a
    temporary FTT_ROS_PREFIX instead of the virtualenv."""
    inputs = sorted(ROBOT_MSGS.rglob("*.msg")) + [ROOT / s for s in BUILD_SCRIPTS]
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in inputs)).hexdigest()[:12]
    prefix = Path(tempfile.gettempdir()) / f"ftt-test-interfaces-{digest}"
    if not (prefix / ".built").exists():
        hook = subprocess.run(
            ["bash", str(ROOT / BUILD_SCRIPTS[0])],
            cwd=ROBOT_MSGS.parent,
            env={
                **os.environ,
                "FTT_ROS_PREFIX": str(prefix),
                "FTT_ROS_INTERFACES": ROBOT_MSGS.name,
            },
            capture_output=True,
            text=True,
            timeout=900,
        )
        assert hook.returncode == 0, hook.stdout + hook.stderr
        assert "ftt_robot_msgs" in hook.stdout.splitlines()[-1]  # built and imported
        (prefix / ".built").touch()
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"

    def joined(name, value):
        return os.pathsep.join(p for p in (value, os.environ.get(name)) if p)

    return {
        "PYTHONPATH": joined("PYTHONPATH", str(prefix / "lib" / version / "site-packages")),
        "LD_LIBRARY_PATH": joined("LD_LIBRARY_PATH", str(prefix / "lib")),
        "AMENT_PREFIX_PATH": joined("AMENT_PREFIX_PATH", f"{prefix}{os.pathsep}{sys.prefix}"),
    }
