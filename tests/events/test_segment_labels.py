"""One name per segment: "Leg N · #k" for masters, "#k.j" for their reasons."""

import pytest

from events.models import SegmentType
from events.selectors.labels import leg_numbers, segment_label
from events.services import logs, segments
from tests.support.modes import start_auto

# On SpatiaLite too: the labels are numbered by window functions in SQL of its own.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]


def test_masters_are_numbered_per_leg_in_driving_order_and_reasons_under_them(leg):
    a1 = start_auto(leg)
    i1 = segments.report_mode(leg, SegmentType.ITO).master
    reason = segments.add_ito_child(i1, reason="unassigned")
    a2 = start_auto(leg)
    numbers = leg_numbers(leg.pk)
    assert numbers[a1.pk] == "1"
    assert numbers[i1.pk] == "2"
    assert numbers[a2.pk] == "3"
    assert numbers[reason.pk].startswith("2.")
    assert segment_label(a2) == f"Leg {leg.number} · #3"


def test_numbering_starts_again_in_the_next_leg(leg):
    segments.report_mode(leg, SegmentType.AUTO)
    second = logs.create_leg(shift=leg.shift)
    first_of_second = start_auto(second)
    assert segment_label(first_of_second) == f"Leg {second.number} · #1"
