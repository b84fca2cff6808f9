"""Fixtures for the collector tests that start real processes (marker ``ros``)."""

import importlib
import os

import pytest

from events.models import Vehicle
from events.services import logs
from rosbridge_app.models import Collector
from tests.support.ros import (
    Processes,
    RosClient,
    copy_default_params,
    database_url,
    wait_for,
)

VEHICLE = "ros-bot"


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
