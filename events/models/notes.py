import uuid

from django.db import models
from django.utils.translation import gettext_lazy as _

from events.models.changes import tracked
from events.models.configuration import Personnel
from events.models.hierarchy import Segment


class Note(models.Model):
    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    segment = models.ForeignKey(
        Segment, on_delete=models.CASCADE, related_name="notes", verbose_name=_("segment")
    )
    author = models.ForeignKey(
        Personnel,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="notes",
        verbose_name=_("author"),
    )
    text = models.TextField(verbose_name=_("text"))
    created = models.DateTimeField(verbose_name=_("created"))
    edited = models.DateTimeField(verbose_name=_("edited"))
    history = tracked()

    class Meta:
        verbose_name = _("note")
        verbose_name_plural = _("notes")
        ordering = ["created", "id"]

    def __str__(self):
        return self.text[:40]
