"""The one table of the shared plumbing: which job workers are alive."""

from django.conf import settings
from django.db import models


class JobWorker(models.Model):
    """A running ``manage.py ftt_worker``; it renews ``beat`` while it lives.

    django-tasks leaves a task "running" forever when its worker is killed;
    this row is how another worker tells a dead worker from a busy one.
    """

    worker_id = models.CharField(max_length=64, primary_key=True)
    host = models.CharField(max_length=255)
    pid = models.IntegerField()
    started = models.DateTimeField()
    beat = models.DateTimeField()

    def __str__(self):
        return f"job worker {self.worker_id}"


class Job(models.Model):
    """What every row that a background job works on shows: its state and outcome."""

    class Status(models.TextChoices):
        QUEUED = "queued", "queued"
        RUNNING = "running", "running"
        DONE = "done", "done"
        FAILED = "failed", "failed"

    status = models.CharField(max_length=10, choices=Status.choices, default=Status.QUEUED)
    message = models.CharField(max_length=200, blank=True, help_text="The step running now.")
    error = models.TextField(blank=True)
    requested_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="+",
    )
    created = models.DateTimeField(auto_now_add=True)
    updated = models.DateTimeField(auto_now=True)
    finished = models.DateTimeField(null=True, blank=True)

    class Meta:
        abstract = True
        ordering = ["-created", "-id"]

    @property
    def is_finished(self) -> bool:
        return self.status in (self.Status.DONE, self.Status.FAILED)
