"""Parallel writers on real, separate database connections cannot break the rules."""

import threading
from concurrent.futures import ThreadPoolExecutor

import pytest
from django.db import connection, connections

from common.errors import RuleViolation
from events.models import Leg, Segment, Shift
from events.services import logs, segments

# On SpatiaLite too: row locks on PostgreSQL, the write lock on SpatiaLite.
pytestmark = [
    pytest.mark.spatialite,
    pytest.mark.postgis_only,
    pytest.mark.django_db(transaction=True),
]

WRITERS = 8


def run_in_parallel(func, args_list):
    """Start all calls at the same moment, each on its own connection."""
    barrier = threading.Barrier(len(args_list))

    def worker(args):
        try:
            barrier.wait()
            return func(*args)
        finally:
            connections.close_all()

    with ThreadPoolExecutor(max_workers=len(args_list)) as pool:
        return list(pool.map(worker, args_list))


@pytest.fixture(autouse=True)
def _needs_postgres():
    if connection.vendor != "postgresql":
        pytest.skip("row locks are a PostgreSQL feature")


def test_parallel_shift_creation_for_one_vehicle_leaves_one_open_shift(test_event, vehicle):
    created = run_in_parallel(
        lambda: logs.create_shift(test_event=test_event, vehicle=vehicle), [()] * WRITERS
    )
    assert len({s.pk for s in created}) == WRITERS
    assert Shift.objects.filter(vehicle=vehicle, end__isnull=True).count() == 1
    numbers = sorted(Shift.objects.filter(test_event=test_event).values_list("number", flat=True))
    assert numbers == list(range(1, WRITERS + 1))


def test_parallel_leg_creation_leaves_one_open_leg(shift):
    run_in_parallel(lambda: logs.create_leg(shift=shift), [()] * WRITERS)
    assert Leg.objects.filter(shift=shift, end__isnull=True).count() == 1
    assert Leg.objects.filter(shift=shift).count() == WRITERS


def test_parallel_mode_reports_keep_one_open_master_and_no_overlap(leg):
    modes = [("ito",), ("auto",)] * (WRITERS // 2)
    run_in_parallel(lambda mode: segments.report_mode(leg, mode), modes)
    masters = list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start", "id"))
    assert sum(m.end is None for m in masters) == 1
    for before, after in zip(masters, masters[1:], strict=False):
        assert before.end is not None and before.end <= after.start
        assert before.segment_type_id != after.segment_type_id
    for master in masters:
        if master.segment_type_id == "ito":
            assert master.children.filter(ito_reason="unassigned").exists()


def test_parallel_manual_segments_share_one_ito_master(leg):
    segments.report_mode(leg, "auto")
    children = run_in_parallel(
        lambda reason: segments.new_manual_segment(leg, reason=reason), [("planner",)] * WRITERS
    )
    ito_masters = Segment.objects.filter(leg=leg, parent__isnull=True, segment_type="ito")
    assert ito_masters.count() == 1
    assert {c.parent_id for c in children} == {ito_masters.get().pk}
    # The switch itself adds "unassigned"; every operator's reason is kept too.
    assert ito_masters.get().children.filter(ito_reason="planner").count() == WRITERS


def test_closing_a_shift_while_robot_and_operators_write_leaves_nothing_open(leg):
    # The close lands at a random point among the writers; whatever order the
    # database picks, every writer either finishes before it or is refused.
    for _ in range(6):
        shift = logs.create_shift(test_event=leg.shift.test_event, vehicle=leg.shift.vehicle)
        this_leg = logs.create_leg(shift=shift)
        master = segments.report_mode(this_leg, "ito").master

        def act(kind, shift=shift, leg=this_leg, master=master):
            try:
                if kind == "close":
                    logs.close_shift(shift)
                elif kind == "reason":
                    segments.add_ito_child(master, reason="planner")
                elif kind == "end-reason":
                    segments.close_segment(master.children.first())
                else:
                    segments.report_mode(leg, kind)
            except RuleViolation:
                return "refused"
            return "done"

        kinds = ["close", "reason", "reason", "auto", "ito", "end-reason", "reason", "auto"]
        outcomes = run_in_parallel(act, [(k,) for k in kinds])
        assert set(outcomes) <= {"done", "refused"}
        assert not Segment.objects.filter(leg=this_leg, end__isnull=True).exists()
        assert Leg.objects.get(pk=this_leg.pk).end is not None
