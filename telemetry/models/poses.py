"""Track points.  They always hang off master segments (see events.services)."""

import uuid

from django.contrib.gis.db import models
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models import PoseSource, Segment


class FixStatus(models.IntegerChoices):
    # sensor_msgs/NavSatStatus values, so the collector can store them as-is.
    NO_FIX = -1, _("no fix")
    FIX = 0, _("fix")
    SBAS = 1, _("SBAS-augmented fix")
    GBAS = 2, _("GBAS-augmented fix (RTK)")


class TrackPoint(models.Model):
    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    robot_stamp = models.DateTimeField(null=True, blank=True, verbose_name=_("robot stamp"))
    received = models.DateTimeField(default=timezone.now, verbose_name=_("received"))

    class Meta:
        abstract = True

    def __str__(self):
        return str(_("%(kind)s #%(id)s") % {"kind": self._meta.verbose_name, "id": self.pk})


# Every index is paid for by each stored pose (a 20 000-pose batch spends most of
# its time in PostgreSQL).  The segment key needs no index of its own: the
# composite segment+time index below serves the track reads and the cascade
# from a deleted segment.
class Pose(TrackPoint):
    segment = models.ForeignKey(
        Segment,
        on_delete=models.CASCADE,
        related_name="poses",
        db_index=False,
        verbose_name=_("segment"),
    )
    point = models.PointField(srid=4326, verbose_name=_("point"))
    altitude = models.FloatField(null=True, blank=True, verbose_name=_("altitude"))
    fix_status = models.SmallIntegerField(
        choices=FixStatus.choices, default=FixStatus.FIX, verbose_name=_("fix status")
    )
    horizontal_accuracy = models.FloatField(
        null=True,
        blank=True,
        help_text=_("1-sigma horizontal accuracy in metres, when known."),
        verbose_name=_("horizontal accuracy"),
    )
    pose_source = models.ForeignKey(
        PoseSource,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="poses",
        # Nothing reads poses by source; only deleting a source looks (PROTECT),
        # a rare admin action that may scan the table rather than slow every insert.
        db_index=False,
        verbose_name=_("pose source"),
    )

    class Meta:
        verbose_name = _("pose")
        verbose_name_plural = _("poses")
        ordering = ["robot_stamp", "received", "id"]
        indexes = [
            # The driving order (telemetry/storage/keys.py) to its last key, so
            # reading a track needs no sort; on PostgreSQL the covered columns let
            # the statistics come from the index alone.
            models.Index(
                fields=["segment", "robot_stamp", "received", "id"],
                include=["point", "fix_status"],
                name="pose_segment_time",
            ),
        ]


class LocalPose(TrackPoint):
    # Covered by the composite index, as for Pose.
    segment = models.ForeignKey(
        Segment,
        on_delete=models.CASCADE,
        related_name="local_poses",
        db_index=False,
        verbose_name=_("segment"),
    )
    frame = models.CharField(max_length=200, verbose_name=_("frame"))
    x = models.FloatField(verbose_name=_("x"))
    y = models.FloatField(verbose_name=_("y"))
    yaw = models.FloatField(
        null=True, blank=True, help_text=_("Heading in radians, when known."), verbose_name=_("yaw")
    )

    class Meta:
        verbose_name = _("local pose")
        verbose_name_plural = _("local poses")
        ordering = ["robot_stamp", "received", "id"]
        indexes = [
            # As for Pose: keys in driving order, covering what a track reads, so
            # a local track comes from the index alone without a sort.
            models.Index(
                fields=["segment", "robot_stamp", "received", "id"],
                include=["x", "y", "frame"],
                name="localpose_segment_time",
            ),
        ]
