import uuid

from django.db import models
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models import Segment


def recording_upload_to(instance, filename):
    return f"recordings/segment-{instance.segment.uid}/{filename}"


class Recording(models.Model):
    """A black-box snapshot: the robot's raw messages of a time window, as MCAP."""

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    segment = models.ForeignKey(
        Segment, on_delete=models.CASCADE, related_name="recordings", verbose_name=_("segment")
    )
    file = models.FileField(upload_to=recording_upload_to, max_length=300, verbose_name=_("file"))
    start = models.DateTimeField(verbose_name=_("start"))
    end = models.DateTimeField(verbose_name=_("end"))
    # {topic: {"type": "pkg/msg/Type", "count": n}}
    topics = models.JSONField(default=dict, verbose_name=_("topics"))
    message_count = models.PositiveIntegerField(default=0, verbose_name=_("message count"))
    size = models.PositiveBigIntegerField(default=0, verbose_name=_("size"))
    reason = models.CharField(max_length=100, blank=True, verbose_name=_("reason"))
    received = models.DateTimeField(default=timezone.now, verbose_name=_("received"))

    class Meta:
        verbose_name = _("recording")
        verbose_name_plural = _("recordings")
        ordering = ["start", "id"]

    def __str__(self):
        return self.file.name.rsplit("/", 1)[-1]

    @property
    def duration(self) -> float:
        return (self.end - self.start).total_seconds()
