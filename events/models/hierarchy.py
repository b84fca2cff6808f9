"""Test Event > Shift > Leg > Segment.

Rows here are only ever created, closed and re-opened through
``events.services``; the constraints below are the database's own copy of the
rules those services enforce, so that even a raw write cannot break them.
"""

import uuid
import zoneinfo

from django.conf import settings
from django.contrib.gis.db import models
from django.core.exceptions import ValidationError
from django.db.models import F, Q
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models.catalogues import ItoReason, SegmentType, Weather
from events.models.changes import tracked
from events.models.configuration import Performer, Personnel, PoseSource, Vehicle


def validate_time_zone(value: str) -> None:
    if value not in zoneinfo.available_timezones():
        raise ValidationError(
            _("'%(value)s' is not an IANA time zone name such as Europe/Berlin.") % {"value": value}
        )


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

    modified = models.DateTimeField(
        default=timezone.now, editable=False, verbose_name=_("modified")
    )

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

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    start = models.DateTimeField(db_index=True, verbose_name=_("start"))
    end = models.DateTimeField(null=True, blank=True, verbose_name=_("end"))
    note = models.TextField(blank=True, verbose_name=_("note"))

    class Meta:
        abstract = True

    @property
    def is_open(self) -> bool:
        return self.end is None


class TestEvent(LogEntry):
    __test__ = False  # pytest would otherwise try to collect it as a test class

    location = models.CharField(max_length=500, blank=True, verbose_name=_("location"))
    version = models.CharField(max_length=200, blank=True, verbose_name=_("version"))
    time_zone = models.CharField(
        max_length=64,
        default="UTC",
        validators=[validate_time_zone],
        help_text=_("IANA name, e.g. Europe/Berlin; every time of this event is shown in it."),
        verbose_name=_("time zone"),
    )
    language = models.CharField(
        max_length=8,
        choices=settings.LANGUAGES,
        default="en",
        verbose_name=_("language"),
        help_text=_("The language of this test event's PDF reports."),
    )
    # Set once by events.services.logs.finalise_test_event; from then on
    # operators may not change the event and its figures use `taxonomy`.
    finalised = models.DateTimeField(
        null=True, blank=True, editable=False, verbose_name=_("finalised")
    )
    finalised_by = models.CharField(
        max_length=200, blank=True, editable=False, verbose_name=_("finalised by")
    )
    # The ITO reasons as they were at finalisation: {key: {name, color, counts}}.
    taxonomy = models.JSONField(null=True, blank=True, editable=False)
    history = tracked()

    class Meta:
        verbose_name = _("test event")
        verbose_name_plural = _("test events")
        ordering = ["-start", "-id"]
        constraints = [_ends_after_start("testevent")]
        permissions = [("finalise_testevent", "Can finalise a closed test event")]

    def __str__(self):
        # Location and day may repeat (two runs of one field test): the version
        # and the number tell them apart in admin's choice lists.
        label = self.location or str(_("Test event"))
        if self.start:
            label = f"{label} {self.start:%Y-%m-%d}"
        if self.version:
            label = f"{label} · {self.version}"
        return f"{label} (#{self.pk})" if self.pk else label

    @property
    def tzinfo(self) -> zoneinfo.ZoneInfo:
        return zoneinfo.ZoneInfo(self.time_zone)


class Shift(LogEntry):
    test_event = models.ForeignKey(
        TestEvent, on_delete=models.CASCADE, related_name="shifts", verbose_name=_("test event")
    )
    number = models.PositiveIntegerField(editable=False, verbose_name=_("number"))
    vehicle = models.ForeignKey(
        Vehicle, on_delete=models.PROTECT, related_name="shifts", verbose_name=_("vehicle")
    )
    performer = models.ForeignKey(
        Performer,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="shifts",
        verbose_name=_("performer"),
    )
    test_administrator = models.ForeignKey(
        Personnel,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("test administrator"),
    )
    test_director = models.ForeignKey(
        Personnel,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("test director"),
    )
    safety_officer = models.ForeignKey(
        Personnel,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("safety officer"),
    )
    robot_operator = models.ForeignKey(
        Personnel,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("robot operator"),
    )
    test_intent = models.CharField(max_length=500, blank=True, verbose_name=_("test intent"))
    workspace = models.CharField(max_length=500, blank=True, verbose_name=_("workspace"))
    history = tracked()

    class Meta:
        verbose_name = _("shift")
        verbose_name_plural = _("shifts")
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
        return str(_("Shift %(number)s") % {"number": self.number})


class Leg(LogEntry):
    shift = models.ForeignKey(
        Shift, on_delete=models.CASCADE, related_name="legs", verbose_name=_("shift")
    )
    number = models.PositiveIntegerField(editable=False, verbose_name=_("number"))
    weather = models.ForeignKey(
        Weather,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("weather"),
    )
    default_pose_source = models.ForeignKey(
        PoseSource,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="legs",
        verbose_name=_("default pose source"),
    )
    # GPS fixes the robot's collector estimated lost while logging into this leg
    # (rosbridge_app.collector.losses, added up from its heartbeats).
    fixes_missed = models.PositiveIntegerField(default=0, editable=False)
    recording = models.CharField(
        max_length=500,
        blank=True,
        help_text=_("Where the robot's recording (bag) of this leg is."),
        verbose_name=_("recording"),
    )
    test_case = models.ForeignKey(
        "events.TestCase",
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="legs",
        help_text=_("The planned trial of the test event that this leg drives."),
        verbose_name=_("test case"),
    )
    history = tracked()

    class Meta:
        verbose_name = _("leg")
        verbose_name_plural = _("legs")
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
        return str(_("Leg %(number)s") % {"number": self.number})


# A master's annotation: none.  Reasons (children) carry it; a master keeps every
# field at what a new reason starts with (docs/architecture.md, the rule table).
NO_ANNOTATION = {
    "ito_reason": None,
    "obstacle": "",
    "lighting": "",
    "slope": "",
    "initiator": "safety_driver",
    "severity": "not_applicable",
    "location_type": "",
}


# A master segment: one without a parent (an ITO child's data belongs to its
# master, ``Segment.master``); for expressions that cannot start from
# ``Segment.objects.masters()``.
IS_MASTER = Q(parent__isnull=True)


class SegmentQuerySet(models.QuerySet):
    def masters(self):
        """The master segments."""
        return self.filter(IS_MASTER)

    def children(self):
        """The ITO children: the segments under a master."""
        return self.filter(~IS_MASTER)


class Segment(ChangeStamped):
    """A master is one continuous run in one mode; ITO children carry reasons."""

    objects = SegmentQuerySet.as_manager()
    IS_MASTER = IS_MASTER

    # Who initiated a take-over and how severe it was: the fields regulators'
    # disengagement reports ask for (California DMV); defaults need no tap.
    INITIATORS = (
        ("autonomous_system", _("autonomous system")),
        ("safety_driver", _("safety driver")),
        ("remote_operator", _("remote operator")),
        ("other", _("other")),
    )
    SEVERITIES = (
        ("critical", _("critical")),
        ("problem", _("problem")),
        ("desired", _("desired")),
        ("not_applicable", _("not applicable")),
    )
    NO_ANNOTATION = NO_ANNOTATION
    ANNOTATION_FIELDS = tuple(NO_ANNOTATION)

    uid = models.UUIDField(default=uuid.uuid4, unique=True, editable=False, verbose_name=_("uid"))
    leg = models.ForeignKey(
        Leg, on_delete=models.CASCADE, related_name="segments", verbose_name=_("leg")
    )
    parent = models.ForeignKey(
        "self",
        on_delete=models.CASCADE,
        null=True,
        blank=True,
        related_name="children",
        verbose_name=_("parent"),
    )
    segment_type = models.ForeignKey(
        SegmentType, on_delete=models.PROTECT, related_name="+", verbose_name=_("segment type")
    )
    ito_reason = models.ForeignKey(
        ItoReason,
        on_delete=models.PROTECT,
        null=True,
        blank=True,
        related_name="segments",
        verbose_name=_("ito reason"),
    )
    # The robot's reason for a take-over (params.reason_rules): shown to be
    # confirmed with one tap; statistics count ito_reason, the confirmed one.
    suggested_reason = models.ForeignKey(
        ItoReason,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("suggested reason"),
    )
    obstacle = models.CharField(max_length=500, blank=True, verbose_name=_("obstacle"))
    lighting = models.CharField(max_length=500, blank=True, verbose_name=_("lighting"))
    slope = models.CharField(max_length=500, blank=True, verbose_name=_("slope"))
    initiator = models.CharField(
        max_length=32,
        choices=INITIATORS,
        default=NO_ANNOTATION["initiator"],
        verbose_name=_("initiator"),
    )
    severity = models.CharField(
        max_length=32,
        choices=SEVERITIES,
        default=NO_ANNOTATION["severity"],
        verbose_name=_("severity"),
    )
    # Free text with suggestions (settings.FTT_LOCATION_TYPES: field, road, yard, …).
    location_type = models.CharField(max_length=64, blank=True, verbose_name=_("location type"))
    start_position = models.PointField(
        srid=4326, null=True, blank=True, verbose_name=_("start position")
    )
    start_local_x = models.FloatField(null=True, blank=True, verbose_name=_("start local x"))
    start_local_y = models.FloatField(null=True, blank=True, verbose_name=_("start local y"))
    start_local_frame = models.CharField(
        max_length=200, blank=True, verbose_name=_("start local frame")
    )
    start = models.DateTimeField(verbose_name=_("start"))
    end = models.DateTimeField(null=True, blank=True, verbose_name=_("end"))
    robot_stamp = models.DateTimeField(
        null=True,
        blank=True,
        help_text=_("The robot's own clock at the mode switch."),
        verbose_name=_("robot stamp"),
    )
    # Seconds the start may lie before `start`: the robot's mode message had no
    # stamp of its own (rosbridge_app.collector.mode_timing); null: not known
    # or not needed (a stamped message, an operator's entry).
    start_uncertainty = models.FloatField(
        null=True, blank=True, help_text=_("Seconds before its start the segment may have begun.")
    )
    # When an operator last set reason, obstacle, lighting or slope (never: null).
    # Imports merge the annotation by this stamp, the rest of the row by `modified`.
    annotated = models.DateTimeField(
        null=True, blank=True, editable=False, verbose_name=_("annotated")
    )
    history = tracked()

    class Meta:
        verbose_name = _("segment")
        verbose_name_plural = _("segments")
        ordering = ["-start", "-id"]
        indexes = [
            models.Index(fields=["leg", "start"], name="segment_leg_start"),
            # Masters in labels' driving order: their numbering reads it without sorting.
            models.Index(
                fields=["leg", "start", "id"],
                condition=Q(parent__isnull=True),
                name="segment_master_order",
            ),
        ]
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
                condition=Q(parent__isnull=False) | Q(**NO_ANNOTATION),
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
        # The GUI's "Leg 2 · #7.1" where a reader put it there (events.selectors.labels);
        # the model alone knows only its id.
        if label := getattr(self, "label", None):
            return label
        words = _("%(mode)s reason #%(id)s") if self.parent_id else _("%(mode)s master #%(id)s")
        return str(words % {"mode": self.segment_type_id.upper(), "id": self.pk})

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

    @staticmethod
    def reason_unassigned(ito_reason_id: str | None) -> bool:
        """Whether a take-over reason naming ``ito_reason_id`` has no annotation yet
        (Unassigned); for rows read without the model too (the statistics' rows)."""
        return ito_reason_id in (None, ItoReason.UNASSIGNED)

    @property
    def unannotated(self) -> bool:
        """A take-over reason (a child) with no annotation yet: the cockpit marks it and
        offers the robot's suggestion for it; statistics count the suggestion then."""
        return self.parent_id is not None and Segment.reason_unassigned(self.ito_reason_id)
