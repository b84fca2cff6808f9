"""Serializers check the shape of a request (types, lengths, existing ids).

Whether the request is allowed in the current state is decided by
``events.services``; views hand ``validated_data`` to those functions.
"""

from datetime import timedelta

from django.db.models import IntegerField
from django.utils import timezone
from django.utils.functional import lazy
from django.utils.translation import gettext
from rest_framework import serializers
from rest_framework_gis.fields import GeometryField

from events import rules
from events.models import (
    ItoReason,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    SegmentType,
    Shift,
    TestEvent,
    Vehicle,
    Weather,
)
from events.selectors.labels import label, legs_numbers, short_label
from events.selectors.segments import touched_by
from events.services import logs
from events.services.segments import (
    LATITUDE_RANGE,
    LONGITUDE_RANGE,
    MODES,
    GpsPosition,
    LocalPosition,
)


class PrimaryKeyField(serializers.PrimaryKeyRelatedField):
    """A reference by id. Integer ids must be integers: the database would quietly turn
    1.5 or true into row 1.  A robot account may only name rows of its own vehicles."""

    def to_internal_value(self, data):
        if isinstance(self.get_queryset().model._meta.pk, IntegerField):
            digits = isinstance(data, str) and data.isascii() and data.isdigit()
            if isinstance(data, bool) or not (isinstance(data, int) or digits):
                self.fail("incorrect_type", data_type=type(data).__name__)
        elif isinstance(data, str) and "\x00" in data:
            # No key holds a NUL, and PostgreSQL refuses to even compare one.
            self.fail("does_not_exist", pk_value=data)
        row = super().to_internal_value(data)
        request = self.context.get("request")
        if request is not None:
            rules.check_robot_target(request.user, row)
        return row


class ServiceSerializer(serializers.ModelSerializer):
    """Fields in ``Meta.create_only_fields`` (parents, client uid) are fixed once a row exists."""

    serializer_related_field = PrimaryKeyField

    def get_fields(self):
        fields = super().get_fields()
        if self.instance is not None:
            for name in getattr(self.Meta, "create_only_fields", ()):
                fields[name].read_only = True
                fields[name].required = False
        return fields


class ClientUidMixin(serializers.Serializer):
    # Declared explicitly so that no uniqueness validator runs: a retry with a
    # known uid is answered with the existing row instead of an error.
    uid = serializers.UUIDField(
        required=False,
        help_text="Client-chosen id; sending the same uid again returns the existing row.",
    )


# --- configuration and catalogues -----------------------------------------------------------


class PersonnelSerializer(ServiceSerializer):
    class Meta:
        model = Personnel
        fields = ["id", "name", "institution", "user"]


class PerformerSerializer(ServiceSerializer):
    class Meta:
        model = Performer
        fields = ["id", "institution"]


class VehicleSerializer(ServiceSerializer):
    class Meta:
        model = Vehicle
        fields = [
            "id",
            "key",
            "short_description",
            "long_description",
            "institution",
            "configuration",
            "vin",
        ]


class PoseSourceSerializer(ServiceSerializer):
    class Meta:
        model = PoseSource
        fields = ["id", "key", "short_description", "long_description"]


class WeatherSerializer(ServiceSerializer):
    # What the cockpit shows: the seeded words in the reader's language.
    label = serializers.CharField(source="shown_short", read_only=True)

    class Meta:
        model = Weather
        fields = ["key", "short_description", "long_description", "icon", "label"]
        create_only_fields = ["key"]


class ItoReasonSerializer(ServiceSerializer):
    # What the cockpit shows: the seeded words in the reader's language.
    label = serializers.CharField(source="shown_short", read_only=True)

    class Meta:
        model = ItoReason
        fields = [
            "key",
            "short_description",
            "long_description",
            "color",
            "counts_as_intervention",
            "quick",
            "label",
        ]
        create_only_fields = ["key"]


class SegmentTypeSerializer(ServiceSerializer):
    # What the cockpit shows: the seeded words in the reader's language.
    label = serializers.CharField(source="shown_short", read_only=True)

    class Meta:
        model = SegmentType
        fields = ["key", "short_description", "long_description", "color", "label"]
        read_only_fields = ["key"]


# --- log hierarchy ------------------------------------------------------------------------


class LogEntrySerializer(ClientUidMixin, ServiceSerializer):
    is_open = serializers.BooleanField(read_only=True)
    may_reopen = serializers.SerializerMethodField(
        help_text="Whether this entry may be re-opened now (only a closed test event, not final)."
    )

    def get_may_reopen(self, row) -> bool:
        return logs.may_reopen(row)


class TestEventSerializer(LogEntrySerializer):
    class Meta:
        model = TestEvent
        fields = [
            "id",
            "uid",
            *logs.TEST_EVENT_FIELDS,
            "start",
            "end",
            "is_open",
            "may_reopen",
            "modified",
            "finalised",
            "finalised_by",
        ]
        read_only_fields = ["start", "end"]
        create_only_fields = ["uid"]


class ShiftSerializer(LogEntrySerializer):
    class Meta:
        model = Shift
        fields = [
            "id",
            "uid",
            "test_event",
            "number",
            *logs.SHIFT_FIELDS,
            "start",
            "end",
            "is_open",
            "may_reopen",
            "modified",
        ]
        read_only_fields = ["number", "start", "end"]
        create_only_fields = ["uid", "test_event"]


class LegSerializer(LogEntrySerializer):
    class Meta:
        model = Leg
        fields = [
            "id",
            "uid",
            "shift",
            "number",
            *logs.LEG_FIELDS,
            "start",
            "end",
            "is_open",
            "may_reopen",
            "modified",
        ]
        read_only_fields = ["number", "start", "end"]
        create_only_fields = ["uid", "shift"]


class SegmentSerializer(ServiceSerializer):
    """Only the annotation (reason, obstacle, lighting, slope) is writable here;
    segments are opened and closed through the leg and segment actions."""

    start_position = GeometryField(read_only=True, allow_null=True)
    is_open = serializers.BooleanField(read_only=True)
    is_master = serializers.BooleanField(read_only=True)
    unannotated = serializers.BooleanField(
        read_only=True,
        help_text="A take-over reason with no annotation yet (Unassigned); false for a master.",
    )

    class Meta:
        model = Segment
        fields = [
            "id",
            "uid",
            "leg",
            "parent",
            "segment_type",
            *Segment.ANNOTATION_FIELDS,
            "suggested_reason",
            "start_position",
            "start_local_x",
            "start_local_y",
            "start_local_frame",
            "start",
            "end",
            "robot_stamp",
            "start_uncertainty",
            "is_open",
            "is_master",
            "unannotated",
            "modified",
            "annotated",
        ]
        read_only_fields = [
            "uid",
            "leg",
            "parent",
            "segment_type",
            "suggested_reason",
            "start_local_x",
            "start_local_y",
            "start_local_frame",
            "start",
            "end",
            "robot_stamp",
            "start_uncertainty",
        ]

        extra_kwargs = {"ito_reason": {"allow_null": False}}


def open_take_over_ids(leg_ids) -> dict[int, int | None]:
    """{leg id: whom the quick reasons annotate now (events.rules.open_take_overs)}."""
    found: dict[int, int | None] = dict.fromkeys(leg_ids)
    for leg, pk in rules.open_take_overs(leg_ids).values_list("leg_id", "pk"):
        found[leg] = found[leg] or pk
    return found


# Worded when written out, in the reader's language: the live feed reads these once
# for every open page, whatever language each page is in (live/consumers.py).
_label_later = lazy(label, str)


def touched_rows(segment_ids) -> dict[int, dict]:
    """{changed segment id: {"segments": the rows that change touched, as the API
    shows them, "labels": their labels, "short_labels": the same within their leg,
    "open_take_over": the id of their leg's open take-over now, or None}}, for readers
    that redraw only those rows (the live feed, and the GUI's writes that answer with
    them).  Four queries."""
    touched = touched_by(segment_ids)
    if not touched:
        return {}
    legs = {c.leg_id for rows in touched.values() for c in rows}
    numbers = legs_numbers(legs)
    take_overs = open_take_over_ids(legs)
    return {
        pk: {
            "open_take_over": take_overs[rows[0].leg_id] if rows else None,
            "segments": SegmentSerializer(rows, many=True).data,
            "labels": {c.pk: _label_later(*numbers[c.pk]) for c in rows if c.pk in numbers},
            "short_labels": {c.pk: short_label(numbers[c.pk][1]) for c in rows if c.pk in numbers},
        }
        for pk, rows in touched.items()
    }


class NoteSerializer(ClientUidMixin, ServiceSerializer):
    author_name = serializers.CharField(source="author.name", read_only=True, default=None)

    class Meta:
        model = Note
        fields = ["id", "uid", "segment", "author", "author_name", "text", "created", "edited"]
        read_only_fields = ["created", "edited"]
        create_only_fields = ["uid", "segment", "author"]
        extra_kwargs = {
            "author": {"help_text": "Personnel id; defaults to the person linked to your login."}
        }


# --- rule action payloads -----------------------------------------------------------------


class PositionSerializer(serializers.Serializer):
    """Where the robot was when a segment started; 0.0 is a valid coordinate."""

    longitude = serializers.FloatField(
        required=False, allow_null=True, min_value=LONGITUDE_RANGE[0], max_value=LONGITUDE_RANGE[1]
    )
    latitude = serializers.FloatField(
        required=False, allow_null=True, min_value=LATITUDE_RANGE[0], max_value=LATITUDE_RANGE[1]
    )
    local_x = serializers.FloatField(required=False, allow_null=True)
    local_y = serializers.FloatField(required=False, allow_null=True)
    local_frame = serializers.CharField(
        required=False, allow_blank=True, max_length=200, default=""
    )

    def validate(self, attrs):
        attrs = super().validate(attrs)
        errors = {}
        for a, b in (("longitude", "latitude"), ("local_x", "local_y")):
            if (attrs.get(a) is None) != (attrs.get(b) is None):
                missing = b if attrs.get(b) is None else a
                errors[missing] = [
                    gettext("Give %(a)s and %(b)s together or neither.") % {"a": a, "b": b}
                ]
        if errors:
            raise serializers.ValidationError(errors)
        return attrs

    def positions(self) -> dict:
        data = self.validated_data
        gps = local = None
        if data.get("longitude") is not None:
            gps = GpsPosition(data["longitude"], data["latitude"])
        if data.get("local_x") is not None:
            local = LocalPosition(data["local_x"], data["local_y"], data.get("local_frame", ""))
        return {"gps": gps, "local": local}


class ReasonField(PrimaryKeyField):
    def __init__(self, **kwargs):
        kwargs.setdefault("queryset", ItoReason.objects.all())
        kwargs.setdefault("required", False)
        kwargs.setdefault("help_text", "ITO reason key; 'unassigned' when left out.")
        super().__init__(**kwargs)


class ModeReportSerializer(PositionSerializer):
    mode = serializers.ChoiceField(choices=MODES)
    reason = ReasonField()
    robot_stamp = serializers.DateTimeField(required=False, allow_null=True)
    uid = serializers.UUIDField(
        required=False, allow_null=True, help_text="Id of the master segment a switch opens."
    )


class ManualSegmentSerializer(PositionSerializer):
    reason = ReasonField()
    uid = serializers.UUIDField(
        required=False,
        allow_null=True,
        help_text="Id of the take-over (ITO child) recorded; the same uid again answers it.",
    )
    seconds_ago = serializers.FloatField(
        required=False,
        min_value=0.0,
        max_value=86400.0,
        help_text="How long ago the operator recorded it (a page that kept it while offline "
        "sends this, measured on its own clock, so a wrong tablet clock does not matter); "
        "default: now.",
    )

    def recorded_at(self):
        """When the take-over was recorded: now, or ``seconds_ago`` before now."""
        ago = self.validated_data.get("seconds_ago")
        return None if ago is None else timezone.now() - timedelta(seconds=ago)


class ChildSerializer(serializers.Serializer):
    reason = ReasonField()


class ModeResultSerializer(serializers.Serializer):
    changed = serializers.BooleanField(help_text="False when the mode was already open.")
    segment = SegmentSerializer(help_text="The master segment open now.")


class CurrentLegSerializer(LegSerializer):
    open_segment = SegmentSerializer(read_only=True, allow_null=True)

    class Meta(LegSerializer.Meta):
        fields = [*LegSerializer.Meta.fields, "open_segment"]


def reason_key(validated: dict) -> str:
    reason = validated.get("reason")
    return reason.pk if reason is not None else ItoReason.UNASSIGNED
