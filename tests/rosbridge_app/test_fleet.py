"""The fleet view's read: every logging vehicle with position, mode, last take-over and leg."""

from datetime import timedelta

import pytest
from django.utils import timezone

from events.models import Vehicle
from events.services import logs, segments
from rosbridge_app.selectors.fleet import FORGET_AFTER, fleet
from rosbridge_app.services import collectors
from telemetry.models.poses import FixStatus
from telemetry.services import pose_writes

pytestmark = pytest.mark.django_db


def logging_robot(test_event, key, *, modes, fixes, logging=True):
    """A vehicle with an open shift and leg, its collector logging into it, the
    given (mode, minutes after the leg's start) switches and GPS fixes in the last segment."""
    vehicle = Vehicle.objects.create(key=key, short_description=f"Rover {key}")
    leg = logs.create_leg(shift=logs.create_shift(test_event=test_event, vehicle=vehicle))
    for mode, minute in modes:
        segments.report_mode(leg, mode, at=leg.start + timedelta(minutes=minute))
    master = leg.segments.filter(parent__isnull=True).order_by("-start").first()
    if fixes:
        pose_writes.store_poses(master, fixes)
    collectors.heartbeat(f"{key}-collector", vehicle=vehicle, logging=logging, leg=leg)
    return vehicle, leg


def test_each_logging_vehicle_shows_where_it_is_its_mode_and_last_take_over(test_event):
    a, leg_a = logging_robot(
        test_event,
        "rover-a",
        modes=[("auto", 0), ("ito", 5), ("auto", 7)],
        fixes=[pose_writes.GpsFix(7.1, 50.6), pose_writes.GpsFix(7.2, 50.7)],
    )
    b, leg_b = logging_robot(
        test_event, "rover-b", modes=[("ito", 3)], fixes=[pose_writes.GpsFix(8.0, 51.0)]
    )
    logging_robot(test_event, "parked", modes=[("auto", 0)], fixes=[], logging=False)

    by_key = {entry["vehicle"]["key"]: entry for entry in fleet()}

    assert set(by_key) == {"rover-a", "rover-b"}
    rover_a = by_key["rover-a"]
    assert rover_a["vehicle"] == {"id": a.pk, "key": "rover-a", "name": "Rover rover-a"}
    assert rover_a["mode"] == "auto"
    assert rover_a["mode_since"] == (leg_a.start + timedelta(minutes=7)).isoformat()
    assert rover_a["last_takeover"] == (leg_a.start + timedelta(minutes=5)).isoformat()
    assert rover_a["position"] == pytest.approx([50.7, 7.2])
    assert rover_a["leg"]["id"] == leg_a.pk
    assert rover_a["leg"]["shift"] == leg_a.shift_id
    assert rover_a["leg"]["test_event"] == test_event.pk
    assert rover_a["collector"]["online"] is True
    rover_b = by_key["rover-b"]
    assert (rover_b["mode"], rover_b["position"]) == ("ito", pytest.approx([51.0, 8.0]))
    assert rover_b["last_takeover"] == (leg_b.start + timedelta(minutes=3)).isoformat()


def test_the_position_is_the_end_of_the_track_even_while_a_new_segment_has_none_yet(test_event):
    _, leg = logging_robot(
        test_event,
        "rover",
        modes=[("auto", 0)],
        fixes=[
            pose_writes.GpsFix(7.0, 50.0),
            pose_writes.GpsFix(7.5, 50.5),
            pose_writes.GpsFix(9.0, 52.0, fix_status=FixStatus.NO_FIX),
        ],
    )
    segments.report_mode(leg, "ito", at=leg.start + timedelta(minutes=1))

    (entry,) = fleet()

    assert entry["mode"] == "ito"
    assert entry["position"] == pytest.approx([50.5, 7.5])


def test_a_collector_unheard_of_for_long_is_forgotten_and_before_that_marked_offline(
    test_event,
):
    logging_robot(test_event, "lost", modes=[("auto", 0)], fixes=[])
    later = timezone.now() + timedelta(minutes=1)

    (entry,) = fleet(now=later)

    assert entry["collector"]["online"] is False
    assert fleet(now=later + FORGET_AFTER) == []


def test_a_vehicle_without_take_over_or_fix_shows_none_of_them(test_event):
    logging_robot(test_event, "fresh", modes=[("auto", 0)], fixes=[])

    (entry,) = fleet()

    assert (entry["last_takeover"], entry["position"]) == (None, None)


def test_the_fleet_is_read_in_one_query_however_many_vehicles(
    test_event, django_assert_num_queries
):
    for n in range(3):
        logging_robot(
            test_event, f"rover-{n}", modes=[("ito", n)], fixes=[pose_writes.GpsFix(7.0 + n, 50.0)]
        )

    with django_assert_num_queries(1):
        entries = fleet()

    assert len(entries) == 3
