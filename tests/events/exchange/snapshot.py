"""Everything a user could see of the stored data, independent of ids and of the backend.

Used to compare installations after a round trip; rows are named by uid (or key)
and files by the SHA-256 of their content.
"""

import hashlib

from events.models import (
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    Shift,
    TestEvent,
    Vehicle,
)
from telemetry.models import Image, LocalPose, MapImage, Pose


def _t(value):
    return value.isoformat() if value is not None else None


def _p(point):
    return [point.x, point.y] if point is not None else None


def snapshot(names: bool = False) -> dict:
    """``names`` adds the files' storage names (equal only between separate installations;
    within one test process earlier copies of a file may still occupy a name)."""

    def _file(field):
        with field.open("rb") as handle:
            digest = hashlib.sha256(handle.read()).hexdigest()
        return [digest, field.name] if names else digest

    entry = ("start", "end", "note")
    return {
        "vehicles": sorted(Vehicle.objects.values_list("key", "short_description")),
        "pose_sources": sorted(PoseSource.objects.values_list("key", flat=True)),
        "performers": sorted(Performer.objects.values_list("institution", flat=True)),
        "personnel": sorted(Personnel.objects.values_list("name", "institution")),
        "test_events": sorted(
            [
                str(e.uid),
                *(_t(getattr(e, f)) if f != "note" else e.note for f in entry),
                e.location,
                e.version,
                e.time_zone,
            ]
            for e in TestEvent.objects.all()
        ),
        "shifts": sorted(
            [
                str(s.uid),
                str(s.test_event.uid),
                s.number,
                _t(s.start),
                _t(s.end),
                s.vehicle.key,
                s.performer.institution if s.performer else None,
                s.robot_operator.name if s.robot_operator else None,
                s.test_intent,
            ]
            for s in Shift.objects.all()
        ),
        "legs": sorted(
            [
                str(g.uid),
                str(g.shift.uid),
                g.number,
                _t(g.start),
                _t(g.end),
                g.weather_id,
                g.default_pose_source.key if g.default_pose_source else None,
            ]
            for g in Leg.objects.all()
        ),
        "segments": sorted(
            [
                str(s.uid),
                str(s.leg.uid),
                str(s.parent.uid) if s.parent else None,
                s.segment_type_id,
                s.ito_reason_id,
                s.obstacle,
                _p(s.start_position),
                s.start_local_x,
                s.start_local_y,
                s.start_local_frame,
                _t(s.start),
                _t(s.end),
                _t(s.robot_stamp),
            ]
            for s in Segment.objects.all()
        ),
        "notes": sorted(
            [
                str(n.uid),
                str(n.segment.uid),
                n.author.name if n.author else None,
                n.text,
                _t(n.created),
                _t(n.edited),
            ]
            for n in Note.objects.all()
        ),
        "poses": sorted(
            [
                str(p.uid),
                str(p.segment.uid),
                _p(p.point),
                p.altitude,
                p.fix_status,
                p.horizontal_accuracy,
                p.pose_source.key if p.pose_source else None,
                _t(p.robot_stamp),
                _t(p.received),
            ]
            for p in Pose.objects.select_related("segment", "pose_source")
        ),
        "local_poses": sorted(
            [
                str(p.uid),
                str(p.segment.uid),
                p.frame,
                p.x,
                p.y,
                p.yaw,
                _t(p.robot_stamp),
                _t(p.received),
            ]
            for p in LocalPose.objects.select_related("segment")
        ),
        "maps": sorted(
            [
                str(m.uid),
                str(m.shift.uid),
                m.frame,
                m.width,
                m.height,
                m.resolution,
                m.origin_x,
                m.origin_y,
                m.origin_yaw,
                m.checksum,
                _t(m.robot_stamp),
                _t(m.received),
                _file(m.image),
            ]
            for m in MapImage.objects.all()
        ),
        "images": sorted(
            [
                str(i.uid),
                str(i.segment.uid),
                i.description,
                _t(i.robot_stamp),
                _t(i.received),
                _file(i.image),
            ]
            for i in Image.objects.all()
        ),
    }
