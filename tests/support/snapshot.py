"""Everything a user could see of the stored data, independent of ids and of the backend.

Used to compare installations after a round trip.  Every stored column of every model
of ``events`` and ``telemetry`` is taken, so a column added later is compared without
anyone remembering to list it here.  Rows, and the rows they refer to, are named by
uid (or key, institution, name) and files by the SHA-256 of their content.
"""

import hashlib
import uuid
from datetime import datetime

from django.apps import apps
from django.contrib.gis.geos import Point
from django.db.models.fields.files import FieldFile

from events.models import (
    Announcement,
    Criterion,
    ItoReason,
    Judgement,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    RobotAccount,
    Segment,
    SegmentType,
    Shift,
    TestCase,
    TestEvent,
    Vehicle,
    Weather,
)
from telemetry.models import (
    Image,
    LocalPose,
    MapImage,
    Pose,
    Recording,
    SegmentFigures,
    ThinnedSegment,
)

TABLES = {
    "weather": Weather,
    "segment_types": SegmentType,
    "ito_reasons": ItoReason,
    "vehicles": Vehicle,
    "pose_sources": PoseSource,
    "performers": Performer,
    "personnel": Personnel,
    "test_events": TestEvent,
    "shifts": Shift,
    "legs": Leg,
    "segments": Segment,
    "notes": Note,
    "poses": Pose,
    "local_poses": LocalPose,
    "maps": MapImage,
    "images": Image,
    "recordings": Recording,
}

# The change feed only tells open browsers what changed; it is not test data.
# Robot accounts bind this installation's logins to vehicles, like the accounts
# themselves they stay where they were made.  Segment figures are measured
# from the poses (tests/telemetry/test_segment_figures.py checks them).  Test
# plans (cases, criteria, judgements) are not carried by archives yet: a base
# station defines its own (docs/data-exchange.md says so).  Which masters the
# retention policy thinned is this installation's; an archive carries the poses left.
NOT_RECORDED = {
    Announcement,
    RobotAccount,
    SegmentFigures,
    ThinnedSegment,
    TestCase,
    Criterion,
    Judgement,
}

# Login accounts belong to one installation; archives do not carry them.
LOCAL_COLUMNS = {(Personnel, "user")}


def _name(row):
    """How another installation knows the same row."""
    if row is None:
        return None
    if isinstance(row, Personnel):
        return [row.name, row.institution]
    if isinstance(row, Performer):
        return row.institution
    if hasattr(row, "uid"):
        return str(row.uid)
    return row.key


def _columns(model):
    return [
        f
        for f in model._meta.concrete_fields
        # Database ids are each installation's own; rows are matched by their names.
        if not (f.primary_key and f.name == "id") and (model, f.name) not in LOCAL_COLUMNS
    ]


def _rows(model):
    # Catalogues are seeded in every installation; only the rows the data uses were
    # part of what was recorded, and an emptied installation must look empty.
    used = {
        Weather: Leg.objects.values("weather"),
        SegmentType: Segment.objects.values("segment_type"),
        ItoReason: Segment.objects.values("ito_reason"),
    }
    rows = model.objects.all()
    if model in used:
        rows = rows.filter(pk__in=used[model])
    return rows.select_related(*(f.name for f in _columns(model) if f.is_relation))


def snapshot(names: bool = False) -> dict:
    """``names`` adds the files' storage names (equal only between separate installations;
    within one test process earlier copies of a file may still occupy a name)."""
    # A new model would otherwise stay out of every comparison unnoticed.
    stored = {m for app in ("events", "telemetry") for m in apps.get_app_config(app).get_models()}
    # Change history (simple-history's Historical* models) differs per installation.
    history = {m for m in stored if hasattr(m, "instance_type")}
    unknown = sorted(m.__name__ for m in stored - set(TABLES.values()) - NOT_RECORDED - history)
    assert not unknown, f"snapshot() does not cover {unknown}; add them to TABLES"

    def _value(row, field):
        if field.is_relation:
            return _name(getattr(row, field.name))
        value = getattr(row, field.attname)
        if isinstance(value, FieldFile):
            if not value:
                return None
            with value.open("rb") as handle:
                digest = hashlib.sha256(handle.read()).hexdigest()
            return [digest, value.name] if names else digest
        if isinstance(value, datetime):
            return value.isoformat()
        if isinstance(value, Point):
            return [value.x, value.y]
        if isinstance(value, uuid.UUID):
            return str(value)
        return value

    return {
        table: sorted([_value(row, f) for f in _columns(model)] for row in _rows(model))
        for table, model in TABLES.items()
    }
