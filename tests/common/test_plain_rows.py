"""plain_rows reads a values_list queryset's rows as Django does, on either database."""

from datetime import UTC, datetime, timedelta

import pytest
from django.db import connection
from django.db.models import F

from events.models import Segment
from telemetry.storage import plain_rows

START = datetime(2025, 4, 1, 6, 0, tzinfo=UTC)


def test_rows_are_the_ones_django_reads(leg):
    master = Segment.objects.create(
        leg=leg, segment_type_id="ito", start=START, end=START + timedelta(seconds=1.25),
        start_local_x=1.5, start_local_y=-0.25,
    )  # fmt: skip
    Segment.objects.create(
        leg=leg, parent=master, segment_type_id="ito", ito_reason_id="safety",
        start=START + timedelta(microseconds=123457), obstacle="cone",
    )  # fmt: skip
    rows = Segment.objects.filter(leg=leg).order_by("start", "id")
    columns = ("id", "parent", "ito_reason", "start", "end", "obstacle", "start_local_x")
    read = plain_rows(rows.values_list(*columns, "leg__shift__test_event"))
    assert read == list(rows.values_list(*columns, "leg__shift__test_event"))
    assert [row[1:7] for row in read] == [
        (None, None, START, START + timedelta(seconds=1.25), "", 1.5),
        (master.pk, "safety", START + timedelta(microseconds=123457), None, "cone", None),
    ]
    assert read[0][3].utcoffset() == timedelta(0)
    assert read[0][7] == leg.shift.test_event_id
    assert plain_rows(rows.filter(pk__in=[]).values_list("id")) == []


def test_annotations_and_converted_fields_are_refused(leg):
    with pytest.raises(ValueError, match="annotations"):
        plain_rows(Segment.objects.annotate(n=F("id")).values_list("n"))
    if connection.vendor == "postgresql":
        # A geometry becomes a Python object only through Django's converter.
        with pytest.raises(ValueError, match="convert"):
            plain_rows(Segment.objects.values_list("start_position"))
