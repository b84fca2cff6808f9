"""Generated reports are kept, one row per request, for download later."""

from django.db import models
from django.utils.translation import gettext_lazy as _

from common.models import Job
from events.models import TestEvent


def report_upload_to(instance, filename):
    return f"reports/test-event-{instance.test_event_id}/report-{instance.pk or 'new'}.pdf"


class Report(Job):
    test_event = models.ForeignKey(
        TestEvent, on_delete=models.CASCADE, related_name="reports", verbose_name=_("test event")
    )
    progress = models.FloatField(default=0.0, help_text=_("0 to 1."), verbose_name=_("progress"))
    options = models.JSONField(default=dict, blank=True, verbose_name=_("options"))
    pdf = models.FileField(upload_to=report_upload_to, blank=True, verbose_name=_("pdf"))
    provisional = models.BooleanField(
        default=False,
        help_text=_("Made while the test event had open segments."),
        verbose_name=_("provisional"),
    )

    class Meta(Job.Meta):
        verbose_name = _("report")
        verbose_name_plural = _("reports")
        indexes = [models.Index(fields=["test_event", "created"], name="report_event_created")]

    def __str__(self):
        return f"Report {self.pk} of test event {self.test_event_id} ({self.status})"
