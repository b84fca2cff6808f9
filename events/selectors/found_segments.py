"""Segments found by a search (place, reason, vehicle, time, version), as flat rows
for a map, a GeoJSON file or a spreadsheet."""

from collections import defaultdict

from django.db.models import F, FloatField, Func

from events.models import Segment, SegmentType
from events.selectors.labels import segment_labels

# A search that finds more than this is asked to narrow down rather than answered.
MAX_FOUND = 200_000

COLUMNS = (
    "id",
    "label",
    "mode",
    "reason",
    "start",
    "end",
    "longitude",
    "latitude",
    "test_event",
    "test_event_location",
    "version",
    "vehicle",
    "shift",
    "leg",
)


def _coordinate(function: str) -> Func:
    # The database reads the point's ordinate: no geometry object per row in Python.
    return Func(F("start_position"), function=function, output_field=FloatField())


def found_rows(segments) -> list[tuple]:
    """One tuple per segment of the filtered queryset, in COLUMNS order and time
    order; MAX_FOUND + 1 bare rows when the search found too many (see too_many)."""
    rows = list(
        segments.order_by("start", "id")
        .annotate(x=_coordinate("ST_X"), y=_coordinate("ST_Y"))
        .values_list(
            "id",
            "segment_type_id",
            "ito_reason_id",
            "start",
            "end",
            "x",
            "y",
            "leg__shift__test_event_id",
            "leg__shift__test_event__location",
            "leg__shift__test_event__version",
            "leg__shift__vehicle__key",
            "leg__shift_id",
            "leg_id",
        )[: MAX_FOUND + 1]
    )
    if too_many(rows):
        return rows
    labels = segment_labels(segments)
    reasons = _reasons_of_masters(segments)
    ito = SegmentType.ITO
    return [
        (
            pk,
            labels.get(pk, ""),
            "ITO" if segment_type == ito else "AUTO",
            reason or " ".join(reasons.get(pk, ())),
            *rest,
        )
        for pk, segment_type, reason, *rest in rows
    ]


def _reasons_of_masters(segments) -> dict[int, list[str]]:
    """{master id: its reasons' keys in driving order}: a take-over's reasons are its children."""
    found = defaultdict(list)
    children = (
        Segment.objects.filter(
            parent_id__in=segments.masters().order_by().values("id"),
            ito_reason__isnull=False,
        )
        .order_by("start", "id")
        .values_list("parent_id", "ito_reason_id")
    )
    for parent, key in children:
        found[parent].append(key)
    return found


def too_many(rows) -> bool:
    return len(rows) > MAX_FOUND
