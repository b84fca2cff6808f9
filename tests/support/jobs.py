"""Running queued jobs in tests: in this process, or as ``manage.py ftt_worker`` processes."""

import os

import pytest
from django.db import connection, transaction
from django_tasks_db.management.commands.db_worker import Worker
from django_tasks_db.models import DBTaskResult

from tests.support.ros import Processes, database_url


def run_queued_jobs() -> int:
    """Run every queued job here, the way ``ftt_worker`` does; returns how many ran.

    The worker's own loop closes the database connection between jobs, which
    a test inside its transaction cannot have; the claim and run are its own.
    """
    worker = Worker(
        queue_names=["default"],
        interval=0,
        batch=True,
        backend_name="default",
        startup_delay=False,
        max_tasks=None,
        worker_id="test-worker",
        excluded_queue_names=[],
    )
    ran = 0
    while True:
        with transaction.atomic():
            job = DBTaskResult.objects.ready().get_locked()
            if job is None:
                return ran
            job.claim(worker.worker_id)
        worker.run_task(job)
        ran += 1


def worker_processes(tmp_path, media_root) -> Processes:
    """Start ``ftt_worker`` processes on this test's (PostgreSQL) database."""
    if connection.vendor != "postgresql":
        pytest.skip("worker processes need a database server (FTT_DATABASE_URL=postgis://)")
    env = dict(os.environ)
    env.update(
        FTT_DATABASE_URL=database_url(connection.settings_dict),
        FTT_DATA_DIR=str(tmp_path / "data"),
        FTT_MEDIA_ROOT=str(media_root),
        FTT_TILE_CACHE=str(tmp_path / "tiles"),
        PYTHONUNBUFFERED="1",
    )
    return _WorkerProcesses(tmp_path, env)


class _WorkerProcesses(Processes):
    def start(self, name: str, *args: str):
        return super().start(
            "ftt_worker", "--no-startup-delay", "--interval", "0.2", *args, name=name
        )
