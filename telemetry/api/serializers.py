"""Shapes of robot-recorded data; storing it is up to ``telemetry.services.pose_writes``."""

import re
import uuid
from typing import Annotated, NotRequired

from django.utils.translation import gettext as _
from pydantic import (
    AwareDatetime,
    BeforeValidator,
    Field,
    Strict,
    TypeAdapter,
    ValidationError,
)
from rest_framework import serializers
from typing_extensions import TypedDict

from common.errors import RuleViolation
from events.api.serializers import ClientUidMixin, PrimaryKeyField, ServiceSerializer
from events.models import PoseSource, Segment
from events.services.segments import LATITUDE_RANGE, LONGITUDE_RANGE
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.models.poses import FixStatus
from telemetry.pictures import MAP_FORMATS
from telemetry.services.map_images import check_map_placement
from telemetry.services.pose_writes import (
    DEFAULT_FIX_STATUS,
    FIX_STATUSES,
    GpsFix,
    MapPose,
)

MAX_BATCH = 5000


def _segments():
    # Everything storing a pose needs (master, leg, scope for the feed) in the one
    # query that checks the id.
    return Segment.objects.select_related("leg__shift", "parent__leg__shift")


class PoseSerializer(ClientUidMixin, ServiceSerializer):
    # Nested sources: input arrives as validated_data["point"] = {"x": .., "y": ..}.
    longitude = serializers.FloatField(
        source="point.x", min_value=LONGITUDE_RANGE[0], max_value=LONGITUDE_RANGE[1]
    )
    latitude = serializers.FloatField(
        source="point.y", min_value=LATITUDE_RANGE[0], max_value=LATITUDE_RANGE[1]
    )
    fix_status = serializers.ChoiceField(choices=FixStatus.choices, default=DEFAULT_FIX_STATUS)
    segment = PrimaryKeyField(
        queryset=_segments(), help_text="Stored on the master when a child segment is given."
    )

    class Meta:
        model = Pose
        fields = [
            "id",
            "uid",
            "segment",
            "longitude",
            "latitude",
            "altitude",
            "fix_status",
            "horizontal_accuracy",
            "pose_source",
            "robot_stamp",
            "received",
        ]
        read_only_fields = ["received"]
        extra_kwargs = {
            "pose_source": {"help_text": "Defaults to the leg's default pose source."},
        }


class PoseByIdSerializer(serializers.Serializer):
    """The answer to a single pose stored the quick way (telemetry.api.single_pose),
    in PoseSerializer's shape; what it accepts is checked by ``sent_pose``.  Its
    fields are declared once here: a ModelSerializer builds them from the model
    on every request, a third of a single pose's time in Python."""

    id = serializers.IntegerField(read_only=True)
    uid = serializers.UUIDField(read_only=True)
    segment = serializers.IntegerField(source="segment_id", read_only=True)
    longitude = serializers.FloatField(source="point.x", read_only=True)
    latitude = serializers.FloatField(source="point.y", read_only=True)
    altitude = serializers.FloatField(read_only=True)
    fix_status = serializers.ChoiceField(choices=FixStatus.choices, read_only=True)
    horizontal_accuracy = serializers.FloatField(read_only=True)
    pose_source = serializers.IntegerField(source="pose_source_id", read_only=True)
    robot_stamp = serializers.DateTimeField(read_only=True)
    received = serializers.DateTimeField(read_only=True)


def gps_fix(data: dict) -> GpsFix:
    point = data["point"]
    fields = {
        "longitude": point["x"],
        "latitude": point["y"],
        "altitude": data.get("altitude"),
        "fix_status": data.get("fix_status", DEFAULT_FIX_STATUS),
        "horizontal_accuracy": data.get("horizontal_accuracy"),
        "robot_stamp": data.get("robot_stamp"),
    }
    # Only a fix sent without a uid gets a new one (uuid4 is a system call).
    if data.get("uid") is not None:
        fields["uid"] = data["uid"]
    return GpsFix(**fields)


class LocalPoseSerializer(ClientUidMixin, ServiceSerializer):
    segment = PrimaryKeyField(queryset=_segments())

    class Meta:
        model = LocalPose
        fields = ["id", "uid", "segment", "frame", "x", "y", "yaw", "robot_stamp", "received"]
        read_only_fields = ["received"]


def map_pose(data: dict) -> MapPose:
    pose = MapPose(
        x=data["x"],
        y=data["y"],
        frame=data["frame"],
        yaw=data.get("yaw"),
        robot_stamp=data.get("robot_stamp"),
    )
    if data.get("uid") is not None:
        pose.uid = data["uid"]
    return pose


# The start DRF's DateTimeField (Django's parse_datetime) needs too: pydantic
# alone would also take a number of seconds written as text.
_ISO_DATETIME = re.compile(r"\d{4}-\d\d-\d\d[T ]\d\d:\d\d")


def _text(value):
    if not isinstance(value, str) or not _ISO_DATETIME.match(value):
        raise ValueError("a date-time is written as ISO 8601 text")
    return value


class _FastPoseItem(TypedDict):
    """What PoseItemSerializer accepts, no more (a few inputs it also takes are
    left to it).  Checked into a plain dict: the fields not sent stay out, as
    DRF leaves them, and no model object is made per pose."""

    # An explicit null is refused, as by DRF; a missing uid gets one in gps_fix.
    uid: NotRequired[uuid.UUID]
    longitude: Annotated[
        float, Field(ge=LONGITUDE_RANGE[0], le=LONGITUDE_RANGE[1], allow_inf_nan=False)
    ]
    latitude: Annotated[
        float, Field(ge=LATITUDE_RANGE[0], le=LATITUDE_RANGE[1], allow_inf_nan=False)
    ]
    altitude: NotRequired[Annotated[float | None, Field(allow_inf_nan=False)]]
    fix_status: NotRequired[Annotated[int, Strict()]]
    horizontal_accuracy: NotRequired[Annotated[float | None, Field(allow_inf_nan=False)]]
    # Aware only: DRF reads a naive time in the server's zone.
    robot_stamp: NotRequired[Annotated[AwareDatetime, BeforeValidator(_text)] | None]


_FAST_POSES = TypeAdapter(list[_FastPoseItem])

# A row id as the view's serializer takes it (ids sent as text are left to it).
_RowId = Annotated[int, Strict(), Field(gt=0, lt=2**63)]


class _FastPose(_FastPoseItem):
    """A single pose (``POST poses/``): a batch item's fields, one definition, and
    the ids the storing statement looks up."""

    segment: _RowId
    pose_source: NotRequired[_RowId | None]


_FAST_POSE = TypeAdapter(_FastPose)


def sent_pose(data) -> tuple[int, GpsFix, int | None] | None:
    """(segment id, fix, pose source id) of a single pose as sent, checked in one
    pass of pydantic; None for anything it does not accept, which PoseSerializer
    then checks and answers with its field messages."""
    if not isinstance(data, dict):
        return None
    try:
        item = _FAST_POSE.validate_python(data)
    except ValidationError:
        return None
    if item.get("fix_status", DEFAULT_FIX_STATUS) not in FIX_STATUSES:
        return None
    segment, source = item.pop("segment"), item.pop("pose_source", None)
    return segment, gps_fix(_as_validated(item)), source


def sent_ids(data: dict) -> tuple[int, GpsFix, int | None]:
    """:func:`sent_pose`'s tuple from PoseSerializer's validated data."""
    source = data.get("pose_source")
    return data["segment"].pk, gps_fix(data), source.pk if source is not None else None


class PoseListSerializer(serializers.ListSerializer):
    """Checks a batch of poses in one pass of pydantic's compiled validators, far
    faster than field by field.  Any batch it does not accept whole
    is checked again by DRF, so a wrong batch gets DRF's usual field messages."""

    def to_internal_value(self, data):
        if isinstance(data, list) and len(data) <= MAX_BATCH:
            try:
                items = _FAST_POSES.validate_python(data)
            except ValidationError:
                items = None
            if items is not None and all(
                i.get("fix_status", DEFAULT_FIX_STATUS) in FIX_STATUSES for i in items
            ):
                return [_as_validated(item) for item in items]
        return super().to_internal_value(data)


def _as_validated(item: dict) -> dict:
    # The shape PoseItemSerializer gives (see gps_fix), from pydantic's own dict.
    item["point"] = {"x": item.pop("longitude"), "y": item.pop("latitude")}
    item.setdefault("fix_status", DEFAULT_FIX_STATUS)
    return item


class PoseItemSerializer(PoseSerializer):
    segment = None  # the batch names it once

    class Meta(PoseSerializer.Meta):
        fields = [
            "uid",
            "longitude",
            "latitude",
            "altitude",
            "fix_status",
            "horizontal_accuracy",
            "robot_stamp",
        ]
        list_serializer_class = PoseListSerializer


class BatchSerializer(serializers.Serializer):
    def validate_poses(self, poses):
        uids = [p["uid"] for p in poses if p.get("uid") is not None]
        if len(uids) != len(set(uids)):
            raise serializers.ValidationError(_("Each pose in a batch needs its own uid."))
        return poses


class PoseBatchSerializer(BatchSerializer):
    segment = PrimaryKeyField(queryset=_segments())
    pose_source = PrimaryKeyField(
        queryset=PoseSource.objects.all(), required=False, allow_null=True
    )
    poses = PoseItemSerializer(many=True, max_length=MAX_BATCH)


class LocalPoseItemSerializer(LocalPoseSerializer):
    class Meta(LocalPoseSerializer.Meta):
        fields = ["uid", "frame", "x", "y", "yaw", "robot_stamp"]


class LocalPoseBatchSerializer(BatchSerializer):
    segment = PrimaryKeyField(queryset=_segments())
    poses = LocalPoseItemSerializer(many=True, max_length=MAX_BATCH)


class BatchResultSerializer(serializers.Serializer):
    stored = serializers.IntegerField(help_text="New rows; retried uids are not counted.")


class MapImageSerializer(ClientUidMixin, ServiceSerializer):
    # Which formats a map may be is the services' rule (telemetry.pictures.MAP_FORMATS,
    # checked by store_map); its refusal answers 400 on this field.
    image = serializers.ImageField(
        help_text=f"The map as a {'/'.join(MAP_FORMATS)} file (multipart upload)."
    )

    class Meta:
        model = MapImage
        fields = [
            "id",
            "uid",
            "shift",
            "frame",
            "width",
            "height",
            "resolution",
            "origin_x",
            "origin_y",
            "origin_yaw",
            "image",
            "checksum",
            "robot_stamp",
            "received",
        ]
        read_only_fields = ["checksum", "received"]

    def validate(self, attrs):
        # The placement rules are the services' (one place); here they answer
        # 400 with their field messages, as any other bad field does.
        try:
            check_map_placement(
                **{
                    name: attrs.get(name, 0.0)
                    for name in MapImage.PLACEMENT_FIELDS
                    if name != "frame"
                }
            )
        except RuleViolation as exc:
            raise serializers.ValidationError(exc.message_dict) from exc
        return attrs


class ImageSerializer(ClientUidMixin, ServiceSerializer):
    image = serializers.ImageField(help_text="A photo or camera frame (multipart upload).")

    class Meta:
        model = Image
        fields = ["id", "uid", "segment", "image", "description", "robot_stamp", "received"]
        read_only_fields = ["received"]
        extra_kwargs = {
            "segment": {"help_text": "Stored on the master when a child segment is given."}
        }


class RecordingSerializer(serializers.ModelSerializer):
    """A black-box snapshot; ``file`` is the MCAP download (viewer role)."""

    duration = serializers.FloatField(read_only=True, help_text="Seconds.")
    name = serializers.CharField(source="__str__", read_only=True)
    reason = serializers.SerializerMethodField()

    class Meta:
        model = Recording
        fields = [
            "id",
            "uid",
            "segment",
            "name",
            "file",
            "start",
            "end",
            "duration",
            "topics",
            "message_count",
            "size",
            "reason",
            "received",
        ]
        read_only_fields = fields

    def get_reason(self, recording) -> str:
        """Why it was cut (a trigger FTT names: switch to ITO, on request, bag import),
        in the reader's language."""
        return _(recording.reason) if recording.reason else ""
