"""Shapes of robot-recorded data; storing it is up to ``telemetry.services.recording``."""

from rest_framework import serializers

from events.api.serializers import ClientUidMixin, PrimaryKeyField, ServiceSerializer
from events.models import PoseSource, Segment
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.models.poses import FixStatus
from telemetry.services.recording import GpsFix, MapPose

MAX_BATCH = 5000


class PoseSerializer(ClientUidMixin, ServiceSerializer):
    # Nested sources: input arrives as validated_data["point"] = {"x": .., "y": ..}.
    longitude = serializers.FloatField(source="point.x", min_value=-180, max_value=180)
    latitude = serializers.FloatField(source="point.y", min_value=-90, max_value=90)
    fix_status = serializers.ChoiceField(choices=FixStatus.choices, default=FixStatus.FIX)

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
            "segment": {"help_text": "Stored on the master when a child segment is given."},
            "pose_source": {"help_text": "Defaults to the leg's default pose source."},
        }


def gps_fix(data: dict) -> GpsFix:
    fix = GpsFix(
        longitude=data["point"]["x"],
        latitude=data["point"]["y"],
        altitude=data.get("altitude"),
        fix_status=data.get("fix_status", FixStatus.FIX),
        horizontal_accuracy=data.get("horizontal_accuracy"),
        robot_stamp=data.get("robot_stamp"),
    )
    if data.get("uid") is not None:
        fix.uid = data["uid"]
    return fix


class LocalPoseSerializer(ClientUidMixin, ServiceSerializer):
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


class PoseItemSerializer(PoseSerializer):
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


class BatchSerializer(serializers.Serializer):
    def validate_poses(self, poses):
        uids = [p["uid"] for p in poses if p.get("uid") is not None]
        if len(uids) != len(set(uids)):
            raise serializers.ValidationError("Each pose in a batch needs its own uid.")
        return poses


class PoseBatchSerializer(BatchSerializer):
    segment = PrimaryKeyField(queryset=Segment.objects.all())
    pose_source = PrimaryKeyField(
        queryset=PoseSource.objects.all(), required=False, allow_null=True
    )
    poses = PoseItemSerializer(many=True, max_length=MAX_BATCH)


class LocalPoseItemSerializer(LocalPoseSerializer):
    class Meta(LocalPoseSerializer.Meta):
        fields = ["uid", "frame", "x", "y", "yaw", "robot_stamp"]


class LocalPoseBatchSerializer(BatchSerializer):
    segment = PrimaryKeyField(queryset=Segment.objects.all())
    poses = LocalPoseItemSerializer(many=True, max_length=MAX_BATCH)


class BatchResultSerializer(serializers.Serializer):
    stored = serializers.IntegerField(help_text="New rows; retried uids are not counted.")


class MapImageSerializer(ClientUidMixin, ServiceSerializer):
    image = serializers.ImageField(help_text="The map as a PNG file (multipart upload).")
    width = serializers.IntegerField(min_value=1, max_value=100_000)
    height = serializers.IntegerField(min_value=1, max_value=100_000)

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

    def validate_image(self, upload):
        if getattr(getattr(upload, "image", None), "format", None) != "PNG":
            raise serializers.ValidationError("Upload the map as a PNG image.")
        return upload

    def validate_resolution(self, value):
        if value <= 0:
            raise serializers.ValidationError("Resolution must be positive (metres per cell).")
        return value


class ImageSerializer(ClientUidMixin, ServiceSerializer):
    image = serializers.ImageField(help_text="A photo or camera frame (multipart upload).")

    class Meta:
        model = Image
        fields = ["id", "uid", "segment", "image", "description", "robot_stamp", "received"]
        read_only_fields = ["received"]
        extra_kwargs = {
            "segment": {"help_text": "Stored on the master when a child segment is given."}
        }
