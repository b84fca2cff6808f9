"""Background jobs (requested reports, archive imports) and their worker.

The queue is django-tasks (the backport of Django 6's ``django.tasks``) with
its database backend, django-tasks-db. Why this one: the queue lives in FTT's
own database, SpatiaLite on a laptop or PostgreSQL on a server, so a job is
enqueued in the same transaction as the row that asked for it (no job without
its row, no row without its job) and nothing else has to run: no broker, no
Redis. Huey would need Redis or a second SQLite file, committed apart from the
row; Celery needs a broker. ``manage.py ftt_worker`` runs the jobs;
``scripts/run.sh`` starts one next to the web server.

The library leaves a task "running" for good when its worker dies mid-job
(SIGKILL, power cut, OOM). So every worker keeps a heartbeat (``JobWorker``),
and every worker, at start and then every ``RECOVER_EVERY_S``, looks for
running tasks whose worker is dead: it retries such a task once more, and
after ``MAX_ATTEMPTS`` marks it failed with the reason. The app that owns a
task is told either way (``when_interrupted``), so its own row (a report, an
import) shows "queued again" or "failed: ..." instead of "running".
"""

import logging
import os
import socket
import threading
from collections.abc import Callable
from datetime import timedelta

from django.db import connection, transaction
from django.utils import timezone
from django.utils.crypto import get_random_string
from django.utils.translation import gettext_noop
from django_tasks.base import TaskResultStatus
from django_tasks_db.models import DBTaskResult

from common.deferred_text import deferred
from common.models import JobWorker

log = logging.getLogger(__name__)

BEAT_EVERY_S = 5.0
# A worker whose heart has not beaten for this long is dead, wherever it ran.
DEAD_AFTER = timedelta(seconds=30)
RECOVER_EVERY_S = 10.0
MAX_ATTEMPTS = 2

_interrupted: dict[str, Callable] = {}


def when_interrupted(task):
    """Register ``handler(*args, retried: bool, reason: DeferredText, **kwargs)`` for ``task``.

    Called with the task's own arguments when a worker died while running it.
    """

    def register(handler: Callable) -> Callable:
        _interrupted[task.module_path] = handler
        return handler

    return register


def new_worker_id() -> str:
    host = socket.gethostname()[:40]
    return f"{host}-{os.getpid()}-{get_random_string(8)}"


def beat(worker_id: str) -> None:
    now = timezone.now()
    JobWorker.objects.update_or_create(
        worker_id=worker_id,
        defaults={"beat": now},
        create_defaults={
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "started": now,
            "beat": now,
        },
    )


def forget(worker_id: str) -> None:
    JobWorker.objects.filter(worker_id=worker_id).delete()


def waiting(now=None):
    """What a queued job's row says until a worker takes it."""
    if worker_running(now):
        return deferred(gettext_noop("waiting for the job worker"))
    return deferred(gettext_noop("waiting: no job worker runs (start manage.py ftt_worker)"))


def worker_running(now=None) -> bool:
    """Whether some worker's heart beat recently (else queued jobs wait)."""
    now = now or timezone.now()
    return JobWorker.objects.filter(beat__gte=now - DEAD_AFTER).exists()


def queue_state(now=None) -> tuple[int, float]:
    """Jobs waiting for a worker, and how long the oldest has waited (s)."""
    now = now or timezone.now()
    waiting = DBTaskResult.objects.filter(status=TaskResultStatus.READY)
    oldest = waiting.order_by("enqueued_at").values_list("enqueued_at", flat=True).first()
    return waiting.count(), (now - oldest).total_seconds() if oldest else 0.0


def _alive(worker: JobWorker | None, now) -> bool:
    if worker is None or worker.beat < now - DEAD_AFTER:
        return False
    if worker.host == socket.gethostname():
        # On this machine a dead process is known at once, not after DEAD_AFTER.
        try:
            os.kill(worker.pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
    return True


def recover_interrupted(now=None) -> list[tuple[str, str]]:
    """Retry or fail the running tasks of dead workers; returns (task id, what was done)."""
    now = now or timezone.now()
    done = []
    for result in DBTaskResult.objects.filter(status=TaskResultStatus.RUNNING):
        last = result.worker_ids[-1] if result.worker_ids else ""
        if _alive(JobWorker.objects.filter(worker_id=last).first(), now):
            continue
        outcome = _recover(result.pk, last, now)
        if outcome:
            done.append((str(result.pk), outcome))
    JobWorker.objects.filter(beat__lt=now - DEAD_AFTER * 10).delete()
    return done


def _recover(task_id, worker_id: str, now) -> str | None:
    with transaction.atomic():
        result = DBTaskResult.objects.select_for_update().filter(pk=task_id).first()
        if result is None or result.status != TaskResultStatus.RUNNING:
            return None  # another worker was quicker
        attempts = len(result.worker_ids)
        retried = attempts < MAX_ATTEMPTS
        reason = deferred(
            gettext_noop(
                "The job worker stopped during attempt %(attempt)s of %(attempts)s "
                "(restart or crash of %(worker)s)."
            ),
            attempt=attempts,
            attempts=MAX_ATTEMPTS,
            worker=worker_id or deferred(gettext_noop("an unknown worker")),
        )
        if retried:
            result.status = TaskResultStatus.READY
            result.started_at = None
            result.save(update_fields=["status", "started_at"])
        else:
            result.status = TaskResultStatus.FAILED
            result.finished_at = now
            result.exception_class_path = "common.jobs.WorkerLost"
            result.traceback = reason.english()
            result.save(
                update_fields=["status", "finished_at", "exception_class_path", "traceback"]
            )
        handler = _handler(result)
        if handler is not None:
            args = result.args_kwargs
            handler(*args["args"], retried=retried, reason=reason, **args["kwargs"])
    log.warning("job %s %s: %s", task_id, "queued again" if retried else "failed", reason.english())
    return "retried" if retried else "failed"


def _handler(result: DBTaskResult) -> Callable | None:
    try:
        result.task  # noqa: B018 - importing the task's module registers its handler
    except ImportError:
        return None
    return _interrupted.get(result.task_path)


class Heart(threading.Thread):
    """Beats for a worker and recovers dead workers' tasks, beside the job loop."""

    def __init__(self, worker_id: str):
        super().__init__(name="ftt-job-heart", daemon=True)
        self.worker_id = worker_id
        self.stopped = threading.Event()

    def run(self) -> None:
        since_recovery = 0.0
        try:
            while not self.stopped.wait(BEAT_EVERY_S):
                self._safely(beat, self.worker_id)
                since_recovery += BEAT_EVERY_S
                if since_recovery >= RECOVER_EVERY_S:
                    since_recovery = 0.0
                    self._safely(recover_interrupted)
        finally:
            connection.close()

    def _safely(self, action, *args) -> None:
        try:
            action(*args)
        except Exception:  # a busy or unreachable database: try again next beat
            log.exception("job worker heartbeat")
            connection.close()

    def stop(self) -> None:
        self.stopped.set()
