"""What each master segment's track amounts to, stored as its poses are written.

One row per master and track kind (GPS, local).  The statistics, the segment
list, the comparison and the growth fit read these rows instead of the
poses, so their time does not grow with the number of poses stored
(telemetry.services.segment_figures keeps them, telemetry.selectors.distances
joins them to the segment's neighbours by the one distance rule).
"""

from django.db import models
from django.utils import timezone

from common.uid_sums import EMPTY
from events.models import Segment


class SegmentFigures(models.Model):
    segment = models.ForeignKey(Segment, on_delete=models.CASCADE, related_name="figures")
    mode = models.CharField(max_length=5)
    # Usable points (GPS: fixes other than "no fix"), and GPS fixes without one.
    points = models.PositiveIntegerField(default=0)
    no_fix = models.PositiveIntegerField(default=0)
    # Length of the usable points in driving order (metres), joins not included.
    length = models.FloatField(default=0.0)
    first_x = models.FloatField(null=True)
    first_y = models.FloatField(null=True)
    last_x = models.FloatField(null=True)
    last_y = models.FloatField(null=True)
    # The last usable point's driving-order key: a batch after it is appended.
    last_robot_stamp = models.DateTimeField(null=True)
    last_received = models.DateTimeField(null=True)
    last_id = models.BigIntegerField(null=True)
    # Earliest and latest time of a usable point (robot clock, else arrival).
    first_stamp = models.DateTimeField(null=True)
    last_stamp = models.DateTimeField(null=True)
    min_x = models.FloatField(null=True)
    min_y = models.FloatField(null=True)
    max_x = models.FloatField(null=True)
    max_y = models.FloatField(null=True)
    # Every pose's uid, usable or not, as one order-free sum (common.uid_sums):
    # what a report's data digest covers of the poses.
    uid_sum = models.CharField(max_length=64, default=EMPTY, db_default=EMPTY)

    class Meta:
        constraints = [
            models.UniqueConstraint(fields=["segment", "mode"], name="segment_figures_unique"),
        ]

    def __str__(self):
        return f"{self.mode} figures of segment {self.segment_id}"


class ThinnedSegment(models.Model):
    """A master whose stored poses the retention policy thinned
    (reports.services.pose_retention): its figures were kept from all of them
    and stay; a recount leaves it out."""

    segment = models.OneToOneField(Segment, on_delete=models.CASCADE, related_name="thinning")
    thinned = models.DateTimeField(default=timezone.now)

    def __str__(self):
        return f"segment {self.segment_id} thinned {self.thinned:%Y-%m-%d}"
