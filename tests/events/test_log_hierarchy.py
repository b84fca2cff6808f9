"""Opening and closing test events, shifts and legs."""

from datetime import timedelta

import pytest
from django.core.exceptions import ValidationError
from django.utils import timezone

from common.errors import RuleViolation
from events.models import Leg, Segment, Shift
from events.services import logs, segments


def test_shift_needs_an_open_test_event(test_event, vehicle):
    logs.close_test_event(test_event)
    with pytest.raises(RuleViolation, match="closed"):
        logs.create_shift(test_event=test_event, vehicle=vehicle)


def test_leg_needs_an_open_shift(shift):
    logs.close_shift(shift)
    with pytest.raises(RuleViolation, match="closed"):
        logs.create_leg(shift=shift)


def test_segment_needs_an_open_leg(leg):
    logs.close_leg(leg)
    with pytest.raises(RuleViolation, match="closed"):
        segments.report_mode(leg, "auto")


def test_new_shift_for_a_vehicle_closes_its_open_shift_and_everything_below(leg, vehicle):
    old_shift = leg.shift
    segments.report_mode(leg, "ito")
    new_shift = logs.create_shift(test_event=old_shift.test_event, vehicle=vehicle)

    old_shift.refresh_from_db()
    leg.refresh_from_db()
    assert old_shift.end is not None
    assert leg.end == old_shift.end
    assert not Segment.objects.filter(leg=leg, end__isnull=True).exists()
    assert Segment.objects.filter(leg=leg, end=old_shift.end).count() == 2
    assert new_shift.is_open


def test_vehicles_are_tested_side_by_side(test_event, vehicle, other_vehicle):
    first = logs.create_shift(test_event=test_event, vehicle=vehicle)
    second = logs.create_shift(test_event=test_event, vehicle=other_vehicle)
    first.refresh_from_db()
    assert first.is_open and second.is_open
    leg_a = logs.create_leg(shift=first)
    leg_b = logs.create_leg(shift=second)
    segments.report_mode(leg_a, "auto")
    segments.report_mode(leg_b, "ito")
    assert Segment.objects.filter(parent__isnull=True, end__isnull=True).count() == 2


def test_new_leg_closes_the_open_leg_of_its_shift(leg):
    segments.report_mode(leg, "auto")
    new_leg = logs.create_leg(shift=leg.shift)
    leg.refresh_from_db()
    assert leg.end is not None
    assert new_leg.is_open
    assert Leg.objects.filter(shift=leg.shift, end__isnull=True).get() == new_leg


def test_closing_a_test_event_closes_everything_below_at_the_same_instant(leg):
    segments.report_mode(leg, "ito")
    event = leg.shift.test_event
    at = timezone.now() + timedelta(seconds=5)
    logs.close_test_event(event, at=at)
    assert Shift.objects.get(pk=leg.shift.pk).end == at
    assert Leg.objects.get(pk=leg.pk).end == at
    assert set(Segment.objects.filter(leg=leg).values_list("end", flat=True)) == {at}


def test_closing_twice_is_refused(leg):
    logs.close_leg(leg)
    with pytest.raises(RuleViolation, match="closed"):
        logs.close_leg(leg)


def test_test_event_reopens_but_its_shifts_stay_closed(shift):
    event = shift.test_event
    logs.close_test_event(event)
    logs.reopen_test_event(event)
    event.refresh_from_db()
    shift.refresh_from_db()
    assert event.is_open
    assert not shift.is_open


def test_reopening_an_open_test_event_is_refused(test_event):
    with pytest.raises(RuleViolation, match="already open"):
        logs.reopen_test_event(test_event)


def test_time_zone_must_be_an_iana_name(db):
    with pytest.raises(ValidationError) as exc:
        logs.create_test_event(location="x", time_zone="(UTC+01:00)")
    assert "time_zone" in exc.value.message_dict


def test_unicode_text_and_clearing_fields(test_event):
    logs.update_test_event(test_event, location="Übungsplatz 試験場", note="")
    test_event.refresh_from_db()
    assert test_event.location == "Übungsplatz 試験場"
    assert test_event.note == ""


def test_times_keep_sub_second_precision(db):
    at = timezone.now().replace(microsecond=123456)
    event = logs.create_test_event(location="x", at=at)
    event.refresh_from_db()
    assert event.start == at


def test_moving_an_open_shift_to_a_busy_vehicle_is_refused(test_event, vehicle, other_vehicle):
    logs.create_shift(test_event=test_event, vehicle=vehicle)
    second = logs.create_shift(test_event=test_event, vehicle=other_vehicle)
    with pytest.raises(RuleViolation) as exc:
        logs.update_shift(second, vehicle=vehicle)
    assert "vehicle" in exc.value.message_dict
