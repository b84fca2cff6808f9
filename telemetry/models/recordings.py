import uuid

from django.db import models
from django.utils import timezone

from events.models import Segment


def recording_upload_to(instance, filename):
    return f"recordings/segment-{instance.segment.uid}/{filename}"


class Recording(models.Model):
    """A black-box snapshot: the robot's raw messages of a time window, as MCAP."""

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)
    segment = models.ForeignKey(Segment, on_delete=models.CASCADE, related_name="recordings")
    file = models.FileField(upload_to=recording_upload_to, max_length=300)
    start = models.DateTimeField()
    end = models.DateTimeField()
    # {topic: {"type": "pkg/msg/Type", "count": n}}
    topics = models.JSONField(default=dict)
    message_count = models.PositiveIntegerField(default=0)
    size = models.PositiveBigIntegerField(default=0)
    reason = models.CharField(max_length=100, blank=True)
    received = models.DateTimeField(default=timezone.now)

    class Meta:
        ordering = ["start", "id"]

    def __str__(self):
        return self.file.name.rsplit("/", 1)[-1]

    @property
    def duration(self) -> float:
        return (self.end - self.start).total_seconds()
