"""Storing what the robot measured.

Every row carries the uid the sender gave it, so a sender that retries after
a lost answer (the collector's offline queue, an import run twice) writes each
point once.  Track points and images always belong to a master segment.
"""

import hashlib
import math
import uuid
from dataclasses import dataclass, field
from datetime import datetime

from django.core.files.base import ContentFile
from django.db import transaction
from django.utils import timezone

from events.errors import RuleViolation
from events.models import PoseSource, Segment, Shift
from events.services.segments import GpsPosition
from rosbridge_app.live import announce_row, announce_track, announced
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.models.poses import FixStatus


def master_of(segment: Segment) -> Segment:
    """Data sent for an ITO reason (child) is stored on its master."""
    if segment.parent_id is None:
        return segment
    return Segment.objects.get(pk=segment.parent_id)


@dataclass
class GpsFix:
    longitude: float
    latitude: float
    altitude: float | None = None
    fix_status: int = FixStatus.FIX
    horizontal_accuracy: float | None = None
    robot_stamp: datetime | None = None
    uid: uuid.UUID = field(default_factory=uuid.uuid4)

    def to_pose(self, segment: Segment, source: PoseSource | None, received) -> Pose:
        position = GpsPosition(self.longitude, self.latitude)
        for name in ("altitude", "horizontal_accuracy"):
            value = getattr(self, name)
            if value is not None and not math.isfinite(value):
                raise RuleViolation({name: [f"{name.replace('_', ' ')} must be a finite number."]})
        if self.fix_status not in FixStatus.values:
            raise RuleViolation({"fix_status": [f"Unknown fix status {self.fix_status}."]})
        return Pose(
            uid=self.uid,
            segment=segment,
            point=position.as_point(),
            altitude=self.altitude,
            fix_status=self.fix_status,
            horizontal_accuracy=self.horizontal_accuracy,
            pose_source=source,
            robot_stamp=self.robot_stamp,
            received=received,
        )


@dataclass
class MapPose:
    x: float
    y: float
    frame: str
    yaw: float | None = None
    robot_stamp: datetime | None = None
    uid: uuid.UUID = field(default_factory=uuid.uuid4)

    def to_local_pose(self, segment: Segment, received) -> LocalPose:
        for name in ("x", "y", "yaw"):
            value = getattr(self, name)
            if value is not None and not math.isfinite(value):
                raise RuleViolation({name: [f"{name} must be a finite number."]})
        if not self.frame:
            raise RuleViolation({"frame": ["A local pose needs the name of its map frame."]})
        return LocalPose(
            uid=self.uid,
            segment=segment,
            frame=self.frame,
            x=self.x,
            y=self.y,
            yaw=self.yaw,
            robot_stamp=self.robot_stamp,
            received=received,
        )


@transaction.atomic
def record_poses(
    segment: Segment, fixes: list[GpsFix], pose_source: PoseSource | None = None
) -> int:
    """Store GPS fixes on the segment's master; returns how many were new."""
    master = master_of(segment)
    if pose_source is None:
        pose_source = master.leg.default_pose_source
    now = timezone.now()
    rows = [fix.to_pose(master, pose_source, now) for fix in fixes]
    return _insert_new(Pose, rows)


@transaction.atomic
def record_local_poses(segment: Segment, poses: list[MapPose]) -> int:
    master = master_of(segment)
    now = timezone.now()
    return _insert_new(LocalPose, [pose.to_local_pose(master, now) for pose in poses])


def _insert_new(model, rows) -> int:
    if not rows:
        return 0
    known = set(model.objects.filter(uid__in=[r.uid for r in rows]).values_list("uid", flat=True))
    fresh = [r for r in rows if r.uid not in known]
    model.objects.bulk_create(fresh, batch_size=1000)
    announce_track(rows[0].segment, fresh, local=model is LocalPose)
    return len(fresh)


@transaction.atomic
def record_map(
    shift: Shift,
    *,
    png: bytes,
    frame: str,
    width: int,
    height: int,
    resolution: float,
    origin_x: float,
    origin_y: float,
    origin_yaw: float = 0.0,
    robot_stamp: datetime | None = None,
    checksum: str | None = None,
    uid: uuid.UUID | None = None,
) -> tuple[MapImage, bool]:
    """Store a map for the shift unless it equals the newest one; returns (map, stored)."""
    if uid is not None and (existing := MapImage.objects.filter(uid=uid).first()):
        return existing, False
    for name, value in (
        ("resolution", resolution),
        ("origin_x", origin_x),
        ("origin_y", origin_y),
        ("origin_yaw", origin_yaw),
    ):
        if not math.isfinite(value):
            raise RuleViolation({name: ["Must be a finite number."]})
    if resolution <= 0 or width <= 0 or height <= 0:
        raise RuleViolation("A map needs a positive size and resolution.")
    Shift.objects.select_for_update().get(pk=shift.pk)
    checksum = checksum or hashlib.sha256(png).hexdigest()
    newest = shift.maps.order_by("-received", "-id").first()
    placement = (frame, width, height, resolution, origin_x, origin_y, origin_yaw)
    if (
        newest is not None
        and newest.checksum == checksum
        and placement == tuple(getattr(newest, name) for name in MapImage.PLACEMENT_FIELDS)
    ):
        return newest, False
    map_image = MapImage(
        shift=shift,
        frame=frame,
        width=width,
        height=height,
        resolution=resolution,
        origin_x=origin_x,
        origin_y=origin_y,
        origin_yaw=origin_yaw,
        checksum=checksum,
        robot_stamp=robot_stamp,
    )
    if uid is not None:
        map_image.uid = uid
    map_image.image.save(f"{map_image.uid}.png", ContentFile(png), save=False)
    map_image.save()
    return announced(map_image), True


@transaction.atomic
def attach_image(
    segment: Segment,
    *,
    content: bytes,
    filename: str = "image.jpg",
    description: str = "",
    robot_stamp: datetime | None = None,
    uid: uuid.UUID | None = None,
) -> Image:
    """Store a camera frame or an uploaded photo on the segment's master."""
    if uid is not None and (existing := Image.objects.filter(uid=uid).first()):
        return existing
    if not content:
        raise RuleViolation({"image": ["The image is empty."]})
    image = Image(segment=master_of(segment), description=description, robot_stamp=robot_stamp)
    if uid is not None:
        image.uid = uid
    image.image.save(filename, ContentFile(content), save=False)
    image.save()
    return announced(image)


@transaction.atomic
def delete_image(image: Image) -> None:
    announce_row(image, deleted=True)
    image.delete()
