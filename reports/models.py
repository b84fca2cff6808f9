"""Generated reports are kept, one row per request, for download later."""

from django.conf import settings
from django.db import models

from events.models import TestEvent


def report_upload_to(instance, filename):
    return f"reports/test-event-{instance.test_event_id}/report-{instance.pk or 'new'}.pdf"


class Report(models.Model):
    class Status(models.TextChoices):
        QUEUED = "queued", "queued"
        RUNNING = "running", "running"
        DONE = "done", "done"
        FAILED = "failed", "failed"

    test_event = models.ForeignKey(TestEvent, on_delete=models.CASCADE, related_name="reports")
    status = models.CharField(max_length=10, choices=Status.choices, default=Status.QUEUED)
    progress = models.FloatField(default=0.0, help_text="0 to 1.")
    message = models.CharField(max_length=200, blank=True, help_text="The step running now.")
    options = models.JSONField(default=dict, blank=True)
    pdf = models.FileField(upload_to=report_upload_to, blank=True)
    provisional = models.BooleanField(
        default=False, help_text="Made while the test event had open segments."
    )
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
    error = models.TextField(blank=True)

    class Meta:
        ordering = ["-created", "-id"]
        indexes = [models.Index(fields=["test_event", "created"], name="report_event_created")]

    def __str__(self):
        return f"Report {self.pk} of test event {self.test_event_id} ({self.status})"

    @property
    def is_finished(self) -> bool:
        return self.status in (self.Status.DONE, self.Status.FAILED)
