"""What a test event's report shows besides its statistics: its shifts with their
people, the legs with their weather, notes, camera images and the ITO reasons."""

from collections import defaultdict

from events.models import ItoReason, Leg, Note, Segment, Shift, TestEvent
from events.selectors.taxonomy import taxonomy_of
from telemetry.models import Image


def has_segments(event: TestEvent) -> bool:
    return Segment.objects.filter(leg__shift__test_event=event).exists()


def reasons_by_key(event: TestEvent) -> dict[str, ItoReason]:
    """The reasons with the names and colours the event's report uses: a final
    event's frozen taxonomy (events.selectors.taxonomy), else the catalogue."""
    return {
        key: ItoReason(
            key=key,
            short_description=entry["name"],
            color=entry["color"],
            counts_as_intervention=entry["counts"],
        )
        for key, entry in taxonomy_of(event).items()
    }


def shifts_of(event: TestEvent) -> list[Shift]:
    """In time order, with vehicle, performer and people."""
    return list(
        event.shifts.select_related(
            "vehicle",
            "performer",
            "test_director",
            "test_administrator",
            "safety_officer",
            "robot_operator",
        ).order_by("start", "id")
    )


def legs_by_shift(shifts: list[Shift]) -> dict[int, list[Leg]]:
    """{shift id: its legs in time order, with their weather}; every shift a key."""
    grouped = {shift.id: [] for shift in shifts}
    for leg in (
        Leg.objects.filter(shift__in=shifts).select_related("weather").order_by("start", "id")
    ):
        grouped[leg.shift_id].append(leg)
    return grouped


def notes_by_master(event: TestEvent) -> dict[int, list[Note]]:
    """{master segment id: the notes on it and on its ITO children}, oldest first."""
    grouped = defaultdict(list)
    for note in (
        Note.objects.filter(segment__leg__shift__test_event=event)
        .select_related("author", "segment")
        .order_by("created", "id")
    ):
        grouped[note.segment.master_id].append(note)
    return grouped


def images_by_segment(event: TestEvent) -> dict[int, list[Image]]:
    """{segment id: its camera images}, in the order they were taken."""
    grouped = defaultdict(list)
    for image in Image.objects.filter(segment__leg__shift__test_event=event).order_by(
        "robot_stamp", "received", "id"
    ):
        grouped[image.segment_id].append(image)
    return grouped
