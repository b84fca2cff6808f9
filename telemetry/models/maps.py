import uuid

from django.db import models
from django.db.models import Q
from django.utils import timezone

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

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)
    shift = models.ForeignKey(Shift, on_delete=models.CASCADE, related_name="maps")
    frame = models.CharField(max_length=200)
    width = models.PositiveIntegerField(help_text="Cells.")
    height = models.PositiveIntegerField(help_text="Cells.")
    resolution = models.FloatField(help_text="Metres per cell.")
    origin_x = models.FloatField()
    origin_y = models.FloatField()
    origin_yaw = models.FloatField(default=0.0, help_text="Radians.")
    image = models.ImageField(upload_to=map_upload_to)
    checksum = models.CharField(
        max_length=64,
        blank=True,
        help_text="SHA-256 of the grid, to store only changed maps.",
    )
    robot_stamp = models.DateTimeField(null=True, blank=True)
    received = models.DateTimeField(default=timezone.now)

    class Meta:
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
