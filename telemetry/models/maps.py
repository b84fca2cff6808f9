import uuid

from django.db import models
from django.db.models import Q
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models import Shift


def map_upload_to(instance, filename):
    return f"maps/shift-{instance.shift.uid}/{instance.uid}.png"


class MapImage(models.Model):
    """An occupancy grid rendered as an image; the newest one of a shift is current."""

    # What places the image in the map frame; two maps with the same grid and
    # the same placement are the same map.
    PLACEMENT_FIELDS = (
        "frame",
        "width",
        "height",
        "resolution",
        "origin_x",
        "origin_y",
        "origin_yaw",
    )

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    shift = models.ForeignKey(
        Shift, on_delete=models.CASCADE, related_name="maps", verbose_name=_("shift")
    )
    frame = models.CharField(max_length=200, verbose_name=_("frame"))
    width = models.PositiveIntegerField(help_text=_("Cells."), verbose_name=_("width"))
    height = models.PositiveIntegerField(help_text=_("Cells."), verbose_name=_("height"))
    resolution = models.FloatField(help_text=_("Metres per cell."), verbose_name=_("resolution"))
    origin_x = models.FloatField(verbose_name=_("origin x"))
    origin_y = models.FloatField(verbose_name=_("origin y"))
    origin_yaw = models.FloatField(
        default=0.0, help_text=_("Radians."), verbose_name=_("origin yaw")
    )
    image = models.ImageField(upload_to=map_upload_to, verbose_name=_("image"))
    checksum = models.CharField(
        max_length=64,
        blank=True,
        help_text=_("SHA-256 of the grid, to store only changed maps."),
        verbose_name=_("checksum"),
    )
    robot_stamp = models.DateTimeField(null=True, blank=True, verbose_name=_("robot stamp"))
    received = models.DateTimeField(default=timezone.now, verbose_name=_("received"))

    class Meta:
        verbose_name = _("map image")
        verbose_name_plural = _("map images")
        ordering = ["-received", "-id"]
        get_latest_by = ["received", "id"]
        indexes = [models.Index(fields=["shift", "received"], name="map_shift_received")]
        # A map of no cells or of no size cannot be placed on the ground.
        constraints = [
            models.CheckConstraint(
                condition=Q(width__gt=0, height__gt=0, resolution__gt=0),
                name="map_has_a_size",
            )
        ]

    def __str__(self):
        return f"Map {self.frame} {self.width}x{self.height} ({self.received:%H:%M:%S})"
