import uuid

from django.db import models

from events.models.changes import tracked
from events.models.configuration import Personnel
from events.models.hierarchy import Segment


class Note(models.Model):
    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)
    segment = models.ForeignKey(Segment, on_delete=models.CASCADE, related_name="notes")
    author = models.ForeignKey(
        Personnel, on_delete=models.PROTECT, null=True, blank=True, related_name="notes"
    )
    text = models.TextField()
    created = models.DateTimeField()
    edited = models.DateTimeField()
    history = tracked()

    class Meta:
        ordering = ["created", "id"]

    def __str__(self):
        return self.text[:40]
