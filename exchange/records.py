"""How each row looks inside an archive.

Rows refer to each other by what stays the same across installations: log
entries and telemetry by ``uid``, catalogues, vehicles and pose sources by
``key``, performers by institution.  Personnel have no natural key, so they get
an archive-local ``ref`` that other rows use.  Times are ISO 8601 in UTC,
points are ``[longitude, latitude]`` in WGS 84.
"""

import json
from datetime import UTC, datetime

from django.contrib.gis.geos import Point
from django.utils.translation import gettext as _

# Import order: everything a row refers to comes before it.
TABLES = (
    "weather",
    "segment_types",
    "ito_reasons",
    "vehicles",
    "pose_sources",
    "performers",
    "personnel",
    "test_events",
    "basemaps",
    "test_cases",
    "shifts",
    "legs",
    "judgements",
    "segments",
    "notes",
    "poses",
    "local_poses",
    "maps",
    "images",
    "recordings",
    "history",
)
PERSON_ROLES = ("test_administrator", "test_director", "safety_officer", "robot_operator")


class RecordError(ValueError):
    """A record in the archive has a value of the wrong shape."""


def time_out(value: datetime | None) -> str | None:
    return None if value is None else value.astimezone(UTC).isoformat()


def time_in(value, field: str) -> datetime | None:
    if value is None:
        return None
    try:
        parsed = datetime.fromisoformat(value)
    except (TypeError, ValueError):
        raise RecordError(
            _("%(field)s: %(value)s is not an ISO 8601 time.")
            % {"field": field, "value": f"{value!r}"}
        ) from None
    if parsed.tzinfo is None:
        raise RecordError(
            _("%(field)s: %(value)s has no UTC offset.") % {"field": field, "value": f"{value!r}"}
        )
    return parsed


def point_out(point: Point | None) -> list[float] | None:
    return None if point is None else [point.x, point.y]


def point_in(value, field: str) -> Point | None:
    if value is None:
        return None
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int | float) for v in value)
    ):
        raise RecordError(
            _("%(field)s: %(value)s is not [longitude, latitude].")
            % {"field": field, "value": f"{value!r}"}
        )
    return Point(float(value[0]), float(value[1]), srid=4326)


def person_ref(person) -> str | None:
    return None if person is None else f"p{person.pk}"


def catalogue_record(row) -> dict:
    record = {
        "key": row.key,
        "short_description": row.short_description,
        "long_description": row.long_description,
    }
    for extra in ("icon", "color", "counts_as_intervention"):
        if hasattr(row, extra):
            record[extra] = getattr(row, extra)
    return record


def keyed_record(row, *extra: str) -> dict:
    record = {
        "key": row.key,
        "short_description": row.short_description,
        "long_description": row.long_description,
    }
    record.update({name: getattr(row, name) for name in extra})
    return record


def _entry(row) -> dict:
    return {
        "uid": str(row.uid),
        "modified": time_out(row.modified),
        "start": time_out(row.start),
        "end": time_out(row.end),
        "note": row.note,
    }


def test_event_record(event) -> dict:
    return _entry(event) | {
        "location": event.location,
        "version": event.version,
        "time_zone": event.time_zone,
        "language": event.language,
        "finalised": time_out(event.finalised),
        "finalised_by": event.finalised_by,
        "taxonomy": event.taxonomy,
    }


def basemap_record(link) -> dict:
    """A reference to a test event's default basemap: the layer's key, not its file.

    External (URL) layers travel whole; a file layer is linked on import when a
    layer with the same key exists there (a backup carries the files themselves).
    """
    layer = link.layer
    return {
        "test_event": str(link.test_event.uid),
        "key": layer.key,
        "name": layer.name,
        "kind": layer.kind,
        "url": layer.url,
        "attribution": layer.attribution,
        "max_zoom": layer.max_zoom,
    }


def shift_record(shift) -> dict:
    record = _entry(shift) | {
        "test_event": str(shift.test_event.uid),
        "number": shift.number,
        "vehicle": shift.vehicle.key,
        "performer": shift.performer.institution if shift.performer else None,
        "test_intent": shift.test_intent,
        "workspace": shift.workspace,
    }
    for role in PERSON_ROLES:
        record[role] = person_ref(getattr(shift, role))
    return record


def leg_record(leg) -> dict:
    return _entry(leg) | {
        "shift": str(leg.shift.uid),
        "number": leg.number,
        "weather": leg.weather_id,
        "default_pose_source": leg.default_pose_source.key if leg.default_pose_source else None,
        "recording": leg.recording,
        "fixes_missed": leg.fixes_missed,
        "test_case": leg.test_case.key if leg.test_case_id else None,
    }


def segment_record(segment, uids: dict) -> dict:
    """``uids`` maps segment and leg primary keys to uids (one query instead of one per row)."""
    return {
        "uid": str(segment.uid),
        "modified": time_out(segment.modified),
        "leg": uids["leg", segment.leg_id],
        "parent": uids["segment", segment.parent_id] if segment.parent_id else None,
        "segment_type": segment.segment_type_id,
        "ito_reason": segment.ito_reason_id,
        "suggested_reason": segment.suggested_reason_id,
        "obstacle": segment.obstacle,
        "lighting": segment.lighting,
        "slope": segment.slope,
        "initiator": segment.initiator,
        "severity": segment.severity,
        "location_type": segment.location_type,
        "annotated": time_out(segment.annotated),
        "start_position": point_out(segment.start_position),
        "start_local_x": segment.start_local_x,
        "start_local_y": segment.start_local_y,
        "start_local_frame": segment.start_local_frame,
        "start": time_out(segment.start),
        "end": time_out(segment.end),
        "robot_stamp": time_out(segment.robot_stamp),
        "start_uncertainty": segment.start_uncertainty,
    }


def note_record(note, segment_uid: str) -> dict:
    return {
        "uid": str(note.uid),
        "segment": segment_uid,
        "author": person_ref(note.author),
        "text": note.text,
        "created": time_out(note.created),
        "edited": time_out(note.edited),
    }


def pose_record(pose, segment_uid: str, source_key: str | None) -> dict:
    return {
        "uid": str(pose.uid),
        "segment": segment_uid,
        "point": point_out(pose.point),
        "altitude": pose.altitude,
        "fix_status": pose.fix_status,
        "horizontal_accuracy": pose.horizontal_accuracy,
        "pose_source": source_key,
        "robot_stamp": time_out(pose.robot_stamp),
        "received": time_out(pose.received),
    }


def local_pose_record(pose, segment_uid: str) -> dict:
    return {
        "uid": str(pose.uid),
        "segment": segment_uid,
        "frame": pose.frame,
        "x": pose.x,
        "y": pose.y,
        "yaw": pose.yaw,
        "robot_stamp": time_out(pose.robot_stamp),
        "received": time_out(pose.received),
    }


def map_record(map_image) -> dict:
    return {
        "uid": str(map_image.uid),
        "shift": str(map_image.shift.uid),
        "frame": map_image.frame,
        "width": map_image.width,
        "height": map_image.height,
        "resolution": map_image.resolution,
        "origin_x": map_image.origin_x,
        "origin_y": map_image.origin_y,
        "origin_yaw": map_image.origin_yaw,
        "checksum": map_image.checksum,
        "robot_stamp": time_out(map_image.robot_stamp),
        "received": time_out(map_image.received),
        "file": map_image.image.name,
    }


def image_record(image, segment_uid: str) -> dict:
    return {
        "uid": str(image.uid),
        "segment": segment_uid,
        "description": image.description,
        "robot_stamp": time_out(image.robot_stamp),
        "received": time_out(image.received),
        "file": image.image.name,
    }


def recording_record(recording, segment_uid: str) -> dict:
    return {
        "uid": str(recording.uid),
        "segment": segment_uid,
        "start": time_out(recording.start),
        "end": time_out(recording.end),
        "topics": recording.topics,
        "message_count": recording.message_count,
        "size": recording.size,
        "reason": recording.reason,
        "received": time_out(recording.received),
        "file": recording.file.name,
    }


def geometry_out(geometry) -> list | None:
    """A line or multipolygon as its coordinates ([longitude, latitude] pairs)."""
    return None if geometry is None else json.loads(json.dumps(geometry.coords))


def test_case_record(case) -> dict:
    """A test case with its criteria; test cases are named by test event and key."""
    return {
        "test_event": str(case.test_event.uid),
        "key": case.key,
        "title": case.title,
        "description": case.description,
        "area": geometry_out(case.area),
        "route": geometry_out(case.route),
        "planned_runs": case.planned_runs,
        "criteria": [criterion_record(c) for c in case.criteria.all()],
    }


def criterion_record(criterion) -> dict:
    """Criteria have no key of their own: a judgement names one by these values."""
    return {
        "kind": criterion.kind,
        "value": criterion.value,
        "text": criterion.text,
        "reasons": sorted(r.pk for r in criterion.reasons.all()),
    }


def judgement_record(judgement, leg_uid: str | None) -> dict:
    criterion = judgement.criterion
    return {
        "test_event": str(criterion.test_case.test_event.uid),
        "test_case": criterion.test_case.key,
        "criterion": {k: v for k, v in criterion_record(criterion).items() if k != "reasons"},
        "leg": leg_uid,
        "passed": judgement.passed,
        "note": judgement.note,
        "at": time_out(judgement.at),
    }
