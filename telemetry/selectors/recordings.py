"""Black-box snapshots, for the report and the GUI."""

from collections import defaultdict

from django.db.models import Count
from django.utils.formats import number_format
from django.utils.translation import gettext

from telemetry.models import Recording


def recordings_by_master(**filters) -> dict[int, list[Recording]]:
    """{master segment id: its snapshots in time order}, e.g.
    ``recordings_by_master(segment__leg__shift__test_event=event)``."""
    grouped = defaultdict(list)
    for recording in Recording.objects.filter(**filters).order_by("start", "id"):
        grouped[recording.segment_id].append(recording)
    return grouped


def summary(recording: Recording) -> str:
    """One line a person reads (the report: in its language): file, window, topics."""
    return gettext("%(name)s (%(seconds)s s, %(count)s messages, %(size)s MB; %(topics)s)") % {
        "name": recording,
        "seconds": f"{recording.duration:.0f}",
        "count": recording.message_count,
        "size": number_format(recording.size / 1e6, 1),
        "topics": ", ".join(recording.topics) or gettext("no topics"),
    }


def snapshots_per_vehicle() -> dict[int, int]:
    """{vehicle id: snapshots stored for it}, for monitoring."""
    rows = Recording.objects.values("segment__leg__shift__vehicle").annotate(n=Count("id"))
    return {row["segment__leg__shift__vehicle"]: row["n"] for row in rows}
