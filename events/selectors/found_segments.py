"""Segments found by a search (place, reason, vehicle, time, version), as flat rows
for a map, a GeoJSON file or a spreadsheet."""

from collections import defaultdict

from events.models import Segment, SegmentType
from events.selectors.labels import label, numbers_of

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


def found_rows(segments) -> list[dict]:
    """One dict per segment of the filtered queryset, COLUMNS as keys, in time order."""
    rows = list(
        segments.order_by("start", "id").values(
            "id",
            "parent_id",
            "leg_id",
            "segment_type_id",
            "ito_reason__key",
            "start",
            "end",
            "start_position",
            "leg__shift_id",
            "leg__shift__vehicle__key",
            "leg__shift__test_event_id",
            "leg__shift__test_event__location",
            "leg__shift__test_event__version",
        )[: MAX_FOUND + 1]
    )
    if len(rows) > MAX_FOUND:
        return rows
    numbers = numbers_of(segments)
    reasons = _reasons_of_masters([row["id"] for row in rows if row["parent_id"] is None])
    return [_row(row, numbers, reasons) for row in rows]


def _reasons_of_masters(master_ids) -> dict[int, list[str]]:
    """{master id: its reasons' keys in driving order}: a take-over's reasons are its children."""
    found = defaultdict(list)
    children = (
        Segment.objects.filter(parent_id__in=master_ids, ito_reason__isnull=False)
        .order_by("start", "id")
        .values_list("parent_id", "ito_reason__key")
    )
    for parent, key in children:
        found[parent].append(key)
    return found


def _row(row, numbers, reasons) -> dict:
    point = row["start_position"]
    leg_number, number = numbers.get(row["id"], (None, "?"))
    return {
        "id": row["id"],
        "label": label(leg_number, number) if leg_number is not None else "",
        "mode": "ITO" if row["segment_type_id"] == SegmentType.ITO else "AUTO",
        "reason": row["ito_reason__key"] or " ".join(reasons.get(row["id"], ())),
        "start": row["start"],
        "end": row["end"],
        "longitude": point.x if point else None,
        "latitude": point.y if point else None,
        "test_event": row["leg__shift__test_event_id"],
        "test_event_location": row["leg__shift__test_event__location"],
        "version": row["leg__shift__test_event__version"],
        "vehicle": row["leg__shift__vehicle__key"],
        "shift": row["leg__shift_id"],
        "leg": row["leg_id"],
    }


def too_many(rows) -> bool:
    return len(rows) > MAX_FOUND
