"""Background jobs: a job whose worker died is retried once, then failed with the reason."""

from datetime import timedelta

from django.utils import timezone
from django_tasks.base import TaskResultStatus
from django_tasks_db.models import DBTaskResult

from common import jobs
from common.models import JobWorker
from events.services import segments
from reports.models import Report
from reports.services.generation import request_report


def _claim(job: DBTaskResult, worker_id: str) -> None:
    job.refresh_from_db()
    job.claim(worker_id)
    Report.objects.update(status=Report.Status.RUNNING, message="drawing the maps")


def test_a_job_of_a_worker_that_stopped_beating_is_retried_once_then_failed(leg):
    segments.report_mode(leg, "auto")
    report = request_report(leg.shift.test_event, {"no_tiles": True})
    job = DBTaskResult.objects.get()
    now = timezone.now()
    # A worker on another machine: only its heartbeat tells whether it lives.
    JobWorker.objects.create(worker_id="far-1", host="elsewhere", pid=1, started=now, beat=now)
    _claim(job, "far-1")
    assert jobs.recover_interrupted(now) == []  # busy, not dead
    assert jobs.worker_running(now)

    later = now + jobs.DEAD_AFTER + timedelta(seconds=1)
    assert not jobs.worker_running(later)
    assert jobs.recover_interrupted(later) == [(str(job.pk), "retried")]
    report.refresh_from_db()
    assert report.status == Report.Status.QUEUED
    assert "queued again" in report.message and "attempt 1 of 2" in report.message
    job.refresh_from_db()
    assert job.status == TaskResultStatus.READY

    _claim(job, "far-2")  # never beat at all
    assert jobs.recover_interrupted(later) == [(str(job.pk), "failed")]
    report.refresh_from_db()
    assert report.status == Report.Status.FAILED
    assert "stopped during attempt 2 of 2" in report.error and "far-2" in report.error
    job.refresh_from_db()
    assert job.status == TaskResultStatus.FAILED and "far-2" in job.traceback


def test_a_worker_on_this_machine_is_dead_as_soon_as_its_process_is(leg):
    segments.report_mode(leg, "auto")
    request_report(leg.shift.test_event, {"no_tiles": True})
    job = DBTaskResult.objects.get()
    now = timezone.now()
    gone = 2**22 + 12345  # above Linux's largest pid: no such process
    JobWorker.objects.create(
        worker_id="here-1", host=jobs.socket.gethostname(), pid=gone, started=now, beat=now
    )
    _claim(job, "here-1")
    assert jobs.recover_interrupted(now) == [(str(job.pk), "retried")]
