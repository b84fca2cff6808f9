import uuid

from django.db import models
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models import Segment
from events.models.changes import tracked


def image_upload_to(instance, filename):
    suffix = filename.rsplit(".", 1)[-1].lower() if "." in filename else "jpg"
    return f"images/segment-{instance.segment.uid}/{instance.uid}.{suffix}"


class Image(models.Model):
    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    segment = models.ForeignKey(
        Segment, on_delete=models.CASCADE, related_name="images", verbose_name=_("segment")
    )
    image = models.ImageField(upload_to=image_upload_to, verbose_name=_("image"))
    description = models.CharField(max_length=500, blank=True, verbose_name=_("description"))
    robot_stamp = models.DateTimeField(null=True, blank=True, verbose_name=_("robot stamp"))
    received = models.DateTimeField(default=timezone.now, verbose_name=_("received"))
    history = tracked()

    class Meta:
        verbose_name = _("image")
        verbose_name_plural = _("images")
        ordering = ["robot_stamp", "received", "id"]
        indexes = [models.Index(fields=["segment", "received"], name="image_segment_received")]

    def __str__(self):
        return self.description or f"Image {self.pk}"
