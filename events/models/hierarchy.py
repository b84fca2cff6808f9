"""Test Event > Shift > Leg > Segment.

Rows here are only ever created, closed and re-opened through
``events.services``; the constraints below are the database's own copy of the
rules those services enforce, so that even a raw write cannot break them.
"""

import uuid
import zoneinfo

from django.contrib.gis.db import models
from django.core.exceptions import ValidationError
from django.db.models import F, Q
from django.utils import timezone

from events.models.catalogues import ItoReason, SegmentType, Weather
from events.models.changes import tracked
from events.models.configuration import Performer, Personnel, PoseSource, Vehicle


def validate_time_zone(value: str) -> None:
    if value not in zoneinfo.available_timezones():
        raise ValidationError(f"'{value}' is not an IANA time zone name such as Europe/Berlin.")


def _ends_after_start(name: str) -> models.CheckConstraint:
    return models.CheckConstraint(
        condition=Q(end__isnull=True) | Q(end__gte=F("start")),
        name=f"{name}_end_after_start",
    )


class ChangeStamped(models.Model):
    """``modified``: when the row last changed, here or where it was logged.

    Every save stamps it, whoever saves (services, admin); an import keeps the
    archive's stamp (``keep_modified=True``).  It lets an import tell a newer
    copy of a row from a stale one: the later change wins.
    """

    modified = models.DateTimeField(default=timezone.now, editable=False)

    class Meta:
        abstract = True

    def save(self, *args, keep_modified: bool = False, **kwargs):
        if not keep_modified:
            self.modified = timezone.now()
            if kwargs.get("update_fields") is not None:
                kwargs["update_fields"] = {*kwargs["update_fields"], "modified"}
        super().save(*args, **kwargs)


class LogEntry(ChangeStamped):
    """Shared shape of every level: a global id, an interval and a note."""

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)
    start = models.DateTimeField(db_index=True)
    end = models.DateTimeField(null=True, blank=True)
    note = models.TextField(blank=True)

    class Meta:
        abstract = True

    @property
    def is_open(self) -> bool:
        return self.end is None


class TestEvent(LogEntry):
    __test__ = False  # pytest would otherwise try to collect it as a test class

    location = models.CharField(max_length=500, blank=True)
    version = models.CharField(max_length=200, blank=True)
    time_zone = models.CharField(
        max_length=64,
        default="UTC",
        validators=[validate_time_zone],
        help_text="IANA name, e.g. Europe/Berlin; every time of this event is shown in it.",
    )
    # Set once by events.services.logs.finalise_test_event; from then on
    # operators may not change the event and its figures use `taxonomy`.
    finalised = models.DateTimeField(null=True, blank=True, editable=False)
    finalised_by = models.CharField(max_length=200, blank=True, editable=False)
    # The ITO reasons as they were at finalisation: {key: {name, color, counts}}.
    taxonomy = models.JSONField(null=True, blank=True, editable=False)
    history = tracked()

    class Meta:
        ordering = ["-start", "-id"]
        constraints = [_ends_after_start("testevent")]
        permissions = [("finalise_testevent", "Can finalise a closed test event")]

    def __str__(self):
        label = self.location or "Test event"
        return f"{label} {self.start:%Y-%m-%d}" if self.start else label

    @property
    def tzinfo(self) -> zoneinfo.ZoneInfo:
        return zoneinfo.ZoneInfo(self.time_zone)


class Shift(LogEntry):
    test_event = models.ForeignKey(TestEvent, on_delete=models.CASCADE, related_name="shifts")
    number = models.PositiveIntegerField(editable=False)
    vehicle = models.ForeignKey(Vehicle, on_delete=models.PROTECT, related_name="shifts")
    performer = models.ForeignKey(
        Performer,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="shifts",
    )
    test_administrator = models.ForeignKey(
        Personnel, on_delete=models.PROTECT, null=True, blank=True, related_name="+"
    )
    test_director = models.ForeignKey(
        Personnel, on_delete=models.PROTECT, null=True, blank=True, related_name="+"
    )
    safety_officer = models.ForeignKey(
        Personnel, on_delete=models.PROTECT, null=True, blank=True, related_name="+"
    )
    robot_operator = models.ForeignKey(
        Personnel, on_delete=models.PROTECT, null=True, blank=True, related_name="+"
    )
    test_intent = models.CharField(max_length=500, blank=True)
    workspace = models.CharField(max_length=500, blank=True)
    history = tracked()

    class Meta:
        ordering = ["-start", "-id"]
        constraints = [
            _ends_after_start("shift"),
            models.UniqueConstraint(fields=["test_event", "number"], name="shift_number_unique"),
            models.UniqueConstraint(
                fields=["vehicle"],
                condition=Q(end__isnull=True),
                name="one_open_shift_per_vehicle",
            ),
        ]

    def __str__(self):
        return f"Shift {self.number}"


class Leg(LogEntry):
    shift = models.ForeignKey(Shift, on_delete=models.CASCADE, related_name="legs")
    number = models.PositiveIntegerField(editable=False)
    weather = models.ForeignKey(
        Weather, on_delete=models.PROTECT, null=True, blank=True, related_name="+"
    )
    default_pose_source = models.ForeignKey(
        PoseSource, on_delete=models.PROTECT, null=True, blank=True, related_name="legs"
    )
    recording = models.CharField(
        max_length=500,
        blank=True,
        help_text="Where the robot's recording (bag) of this leg is.",
    )
    history = tracked()

    class Meta:
        ordering = ["-start", "-id"]
        constraints = [
            _ends_after_start("leg"),
            models.UniqueConstraint(fields=["shift", "number"], name="leg_number_unique"),
            models.UniqueConstraint(
                fields=["shift"],
                condition=Q(end__isnull=True),
                name="one_open_leg_per_shift",
            ),
        ]

    def __str__(self):
        return f"Leg {self.number}"


class Segment(ChangeStamped):
    """A master is one continuous run in one mode; ITO children carry reasons."""

    # Who initiated a take-over and how severe it was: the fields regulators'
    # disengagement reports ask for (California DMV); defaults need no tap.
    INITIATORS = (
        ("autonomous_system", "autonomous system"),
        ("safety_driver", "safety driver"),
        ("remote_operator", "remote operator"),
        ("other", "other"),
    )
    SEVERITIES = (
        ("critical", "critical"),
        ("problem", "problem"),
        ("desired", "desired"),
        ("not_applicable", "not applicable"),
    )
    ANNOTATION_FIELDS = (
        "ito_reason",
        "obstacle",
        "lighting",
        "slope",
        "initiator",
        "severity",
        "location_type",
    )

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False)
    leg = models.ForeignKey(Leg, on_delete=models.CASCADE, related_name="segments")
    parent = models.ForeignKey(
        "self", on_delete=models.CASCADE, null=True, blank=True, related_name="children"
    )
    segment_type = models.ForeignKey(SegmentType, on_delete=models.PROTECT, related_name="+")
    ito_reason = models.ForeignKey(
        ItoReason,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="segments",
    )
    obstacle = models.CharField(max_length=500, blank=True)
    lighting = models.CharField(max_length=500, blank=True)
    slope = models.CharField(max_length=500, blank=True)
    initiator = models.CharField(max_length=32, choices=INITIATORS, default="safety_driver")
    severity = models.CharField(max_length=32, choices=SEVERITIES, default="not_applicable")
    # Free text with suggestions (settings.FTT_LOCATION_TYPES: field, road, yard, …).
    location_type = models.CharField(max_length=64, blank=True)
    start_position = models.PointField(srid=4326, null=True, blank=True)
    start_local_x = models.FloatField(null=True, blank=True)
    start_local_y = models.FloatField(null=True, blank=True)
    start_local_frame = models.CharField(max_length=200, blank=True)
    start = models.DateTimeField()
    end = models.DateTimeField(null=True, blank=True)
    robot_stamp = models.DateTimeField(
        null=True, blank=True, help_text="The robot's own clock at the mode switch."
    )
    # When an operator last set reason, obstacle, lighting or slope (never: null).
    # Imports merge the annotation by this stamp, the rest of the row by `modified`.
    annotated = models.DateTimeField(null=True, blank=True, editable=False)
    history = tracked()

    class Meta:
        ordering = ["-start", "-id"]
        indexes = [models.Index(fields=["leg", "start"], name="segment_leg_start")]
        constraints = [
            _ends_after_start("segment"),
            models.UniqueConstraint(
                fields=["leg"],
                condition=Q(end__isnull=True, parent__isnull=True),
                name="one_open_master_per_leg",
            ),
            models.CheckConstraint(
                condition=Q(parent__isnull=True) | Q(segment_type=SegmentType.ITO),
                name="segment_children_are_ito",
            ),
            models.CheckConstraint(
                condition=Q(parent__isnull=False)
                | Q(ito_reason__isnull=True, obstacle="", lighting="", slope=""),
                name="segment_masters_have_no_annotation",
            ),
            # Statistics count interventions by reason; a child without one
            # would drop out of every figure.
            models.CheckConstraint(
                condition=Q(parent__isnull=True) | Q(ito_reason__isnull=False),
                name="segment_children_have_a_reason",
            ),
            models.CheckConstraint(
                condition=Q(start_local_x__isnull=True, start_local_y__isnull=True)
                | Q(start_local_x__isnull=False, start_local_y__isnull=False),
                name="segment_local_start_complete",
            ),
        ]

    def __str__(self):
        kind = "child" if self.parent_id else "master"
        return f"{self.segment_type_id.upper()} {kind} #{self.pk}"

    @property
    def is_open(self) -> bool:
        return self.end is None

    @property
    def is_master(self) -> bool:
        return self.parent_id is None

    @property
    def master_id(self) -> int:
        """The id of the master this segment belongs to: its own for a master, its
        parent's for an ITO child (data sent for a child is stored on the master)."""
        return self.pk if self.parent_id is None else self.parent_id

    @property
    def master(self) -> "Segment":
        """The master segment itself; no query for a master, or for a child fetched
        with ``select_related("parent")``."""
        return self if self.parent_id is None else self.parent

    @property
    def is_ito(self) -> bool:
        return self.segment_type_id == SegmentType.ITO
