"""Storing the poses the robot measured: GPS fixes and map-frame poses.

Every row carries the uid the sender gave it, so a sender that retries after
a lost answer (the collector's offline queue, an import run twice) writes each
point once.  Track points always belong to a master segment.  Maps are stored
by telemetry.services.map_images, images and black-box snapshots by
telemetry.services.attachments; the rows are written through the storage
port (telemetry.storage).
"""

import math
import uuid
from dataclasses import dataclass, field
from datetime import datetime

from django.contrib.gis.geos import Point
from django.core.exceptions import ValidationError
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext as _

from common.errors import RuleViolation
from common.retries import refuse_foreign, stored_row
from events import rules
from events.feed import track_announcement
from events.models import PoseSource, Segment
from events.selectors.segments import pose_target
from events.services import deletion
from events.services.finality import final_events, require_amendable
from events.services.segments import GpsPosition
from telemetry import storage
from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus
from telemetry.services.segment_figures import Added, add_to_figures, measure_figures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK
from telemetry.storage.rows import as_uuid

# The fix statuses a pose may carry and the one it gets when none is sent; every
# check of a sent fix reads these.  (FixStatus.values builds a new list on each
# access; this check runs per pose.)
FIX_STATUSES = frozenset(FixStatus.values)
DEFAULT_FIX_STATUS = FixStatus.FIX


@dataclass
class GpsFix:
    longitude: float
    latitude: float
    altitude: float | None = None
    fix_status: int = DEFAULT_FIX_STATUS
    horizontal_accuracy: float | None = None
    robot_stamp: datetime | None = None
    uid: uuid.UUID = field(default_factory=uuid.uuid4)

    def check(self) -> None:
        """The rules every stored fix satisfies, whichever way it is stored."""
        GpsPosition.check(self.longitude, self.latitude)
        for name, value in (
            ("altitude", self.altitude),
            ("horizontal_accuracy", self.horizontal_accuracy),
        ):
            if value is not None and not math.isfinite(value):
                label = name.replace("_", " ")
                message = _("%(name)s must be a finite number.") % {"name": label}
                raise RuleViolation({name: [message]})
        if self.fix_status not in FIX_STATUSES:
            message = _("Unknown fix status %(status)s.") % {"status": self.fix_status}
            raise RuleViolation({"fix_status": [message]})

    def to_pose(self, segment: Segment, source: PoseSource | None, received) -> Pose:
        """The checked, unsaved row (the archive import inserts these itself)."""
        self.check()
        return self.row(segment, source.pk if source is not None else None, received)

    def row(self, segment: Segment, source_id: int | None, received) -> Pose:
        return Pose(
            uid=self.uid,
            segment=segment,
            point=Point(self.longitude, self.latitude, srid=4326),
            altitude=self.altitude,
            fix_status=self.fix_status,
            horizontal_accuracy=self.horizontal_accuracy,
            pose_source_id=source_id,
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

    def check(self) -> None:
        for name in ("x", "y", "yaw"):
            value = getattr(self, name)
            if value is not None and not math.isfinite(value):
                raise RuleViolation(
                    {name: [_("%(name)s must be a finite number.") % {"name": name}]}
                )
        if not self.frame:
            raise RuleViolation({"frame": [_("A local pose needs the name of its map frame.")]})

    def to_local_pose(self, segment: Segment, received) -> LocalPose:
        self.check()
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
def store_poses(
    segment: Segment, fixes: list[GpsFix], pose_source: PoseSource | None = None
) -> int:
    """Store GPS fixes on the segment's master; returns how many were new
    (known uids are skipped, so a retried batch stores nothing twice)."""
    for fix in fixes:
        fix.check()
    if not fixes:
        return 0
    master = segment.master
    source_id = pose_source_id(master, pose_source.pk if pose_source is not None else None)
    received = timezone.now()
    # As for one pose (store_pose): a final event refuses the batch in its insert.
    final = final_events(shifts__legs__segments=master.pk)
    stored = storage.insert_fixes(master, source_id, fixes, received, refused_by=final)
    if not stored and final.exists():
        require_amendable(shifts__legs__segments=master.pk)
        stored = storage.insert_fixes(master, source_id, fixes, received)
    new = {p.uid for p in stored}
    if len(new) < len(fixes):
        refuse_foreign(Pose, [as_uuid(f.uid) for f in fixes], new, segment_id=master.pk)
    add_to_figures(master.pk, GPS_TRACK, stored, announce=track_row(master, local=False))
    return len(new)


def pose_source_id(master: Segment, sent: int | None) -> int | None:
    """The pose source a fix is stored with: the one sent, else its leg's default."""
    return sent if sent is not None else master.leg.default_pose_source_id


def store_pose(
    segment_id: int, fix: GpsFix, source_id: int | None = None, *, writer=None
) -> tuple[Pose, bool]:
    """Store one fix sent for ``segment_id`` on its master, in one short
    transaction with its feed row; (row, True) when stored, (the row stored
    first, False) for a uid already stored on the same master.  ``writer`` is
    checked against the segment (a robot reaches its own vehicles only)."""
    master = pose_target(segment_id)
    if master is None:
        raise ValidationError(
            {"segment": [_('Invalid pk "%(pk)s" - object does not exist.') % {"pk": segment_id}]}
        )
    if writer is not None:
        rules.check_robot_target(writer, master)
    fix.check()
    received = timezone.now()
    source_id = pose_source_id(master, source_id)
    event_id = master.leg.shift.test_event_id
    with transaction.atomic():
        # A final event refuses the pose in the insert itself (no statement of
        # its own); only then is it asked why, and an amendment stores it.
        stored = storage.insert_pose(
            master.pk, fix, source_id, received, refused_by=final_events(pk=event_id)
        )
        if stored is None and final_events(pk=event_id).exists():
            require_amendable(pk=event_id)
            stored = storage.insert_pose(master.pk, fix, source_id, received)
        if stored is not None:
            pk, seen = stored
            point = storage.NewPoint(
                fix.uid, pk, fix.robot_stamp, received, fix.longitude, fix.latitude,
                fix.fix_status != FixStatus.NO_FIX,
            )  # fmt: skip
            # The figures and the feed row are one statement; the row stays locked to the commit.
            add_to_figures(
                master.pk, GPS_TRACK, [point], seen, announce=track_row(master, local=False)
            )
    if stored is None:
        return known_pose(master, fix, source_id), False
    row = fix.row(master, source_id, received)
    row.pk = pk
    return row, True


def known_pose(master: Segment, fix: GpsFix, source_id: int | None) -> Pose:
    """The row stored first under the fix's uid (common.retries)."""
    row = stored_row(Pose, fix.uid, segment_id=master.pk)
    if row is None:
        # The insert found no segment or no pose source.
        if source_id is not None and not PoseSource.objects.filter(pk=source_id).exists():
            message = _('Invalid pk "%(pk)s" - object does not exist.') % {"pk": source_id}
            raise ValidationError({"pose_source": [message]})
        raise ValidationError({"segment": [_("The segment has just been deleted.")]})
    return row


@transaction.atomic
def store_local_pose(segment: Segment, pose: MapPose) -> LocalPose:
    """Store one map-frame pose; the new row, or the row stored first under its
    uid on the same master (common.retries)."""
    uid = as_uuid(pose.uid)
    if store_local_poses(segment, [pose]):
        return LocalPose.objects.filter(uid=uid, segment_id=segment.master_id).latest("id")
    return stored_row(LocalPose, uid, segment_id=segment.master_id)


def _track_point_deleted(sender, instance, **kwargs) -> None:
    # Every write that changes poses keeps the figures: a deleted point is a
    # step less, and its neighbours join (measured again from the poses).
    measure_figures([instance.segment_id], [GPS_TRACK if sender is Pose else LOCAL_TRACK])


def connect() -> None:
    """Deleting a pose or local pose (events.services.deletion) keeps its master's figures."""
    for model in (Pose, LocalPose):
        deletion.deleted.connect(
            _track_point_deleted, sender=model, dispatch_uid=f"ftt-figures-{model.__name__}"
        )


@transaction.atomic
def store_local_poses(segment: Segment, poses: list[MapPose]) -> int:
    """Store map-frame poses on the segment's master; returns how many were new."""
    master = segment.master
    for pose in poses:
        pose.check()
    if poses:
        require_amendable(shifts__legs__segments=master.pk)
    fresh = storage.insert_local_poses(master, poses, timezone.now()) if poses else []
    # The robot's heading for its marker: the yaw of the newest pose stored.
    stored = {point.uid for point in fresh}
    refuse_foreign(LocalPose, [as_uuid(p.uid) for p in poses], stored, segment_id=master.pk)
    heading = next((p.yaw for p in reversed(poses) if as_uuid(p.uid) in stored), None)
    add_to_figures(
        master.pk, LOCAL_TRACK, fresh, announce=track_row(master, local=True, heading=heading)
    )
    return len(fresh)


def track_row(master: Segment, *, local: bool, heading=None):
    """How open browsers learn what the track now holds (add_to_figures' ``announce``):
    the usable points a write added, in driving order, when they follow the
    track's end; else that the track changed inside (a late batch), which they
    read again."""

    def row(added: Added):
        points = [(p.x, p.y) for p in added.points]
        return track_announcement(
            master, points, local=local, heading=heading, inside=not added.appended
        )

    return row
