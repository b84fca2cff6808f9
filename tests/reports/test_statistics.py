"""Statistics of the hand-checkable scenario (see scenario.py for the geometry).

Chi-square quantiles come from the closed-form CDF (scenario.py), not from scipy, so the bounds
are checked against an independent source.
"""

import pytest

from events.services import logs
from reports.selectors.statistics import (
    campaign_runs,
    event_runs,
    event_statistics,
    poisson_estimate,
)
from tests.support.scenario import CHI2_05, CHI2_95, STEP_M, T0, T1, _switch

D_A = 13 * STEP_M
D_M = 4 * STEP_M
T_A = 100 + 240 + 300 + 300
T_M = 60 + 30 + 70


def approx(value):
    return pytest.approx(value, rel=1e-6)


def test_run_distances_include_the_joins_at_each_switch(scenario):
    stats = event_statistics(scenario.event)
    by_id = {run.id: run for run in stats.runs}
    expected_steps = {"A1": 3, "I1": 1, "A2": 2, "A3": 4, "I2": 2, "A4": 4, "I3": 1}
    for name, steps in expected_steps.items():
        assert by_id[scenario.masters[name].id].distance == approx(steps * STEP_M), name


def test_event_totals_ratios_and_interventions(scenario):
    overall = event_statistics(scenario.event).overall
    assert overall.auto_distance == approx(D_A)
    assert overall.manual_distance == approx(D_M)
    assert overall.auto_seconds == T_A
    assert overall.manual_seconds == T_M
    assert overall.autonomy_ratio_distance == approx(13 / 17)
    assert overall.autonomy_ratio_time == approx(T_A / (T_A + T_M))
    # I1 (safety + planner) counts once, I2 (goal) not at all, I3 (unexpected) once.
    assert overall.interventions == 2
    assert overall.interventions_by_reason == {"planner": 1, "safety": 1, "unexpected": 1}
    assert overall.manual_seconds_by_reason == {
        "goal": 30,
        "planner": 40,
        "safety": 60,
        "unexpected": 70,
    }
    assert overall.mean_auto_run == approx(D_A / 4)
    assert overall.max_auto_run == approx(4 * STEP_M)
    assert overall.interventions_per_km == approx(2 / (D_A / 1000))
    assert overall.interventions_per_hour == approx(2 / (T_A / 3600))
    assert not overall.provisional


def test_mdbi_and_mtbi_with_chi_square_bounds(scenario):
    overall = event_statistics(scenario.event).overall
    assert overall.mdbi.value == approx(D_A / 2)
    assert overall.mdbi.lower == pytest.approx(2 * D_A / CHI2_95[6], rel=1e-5)
    assert overall.mdbi.upper == pytest.approx(2 * D_A / CHI2_05[4], rel=1e-5)
    assert overall.mtbi.value == approx(T_A / 2)
    assert overall.mtbi.lower == pytest.approx(2 * T_A / CHI2_95[6], rel=1e-5)
    assert overall.mtbi.upper == pytest.approx(2 * T_A / CHI2_05[4], rel=1e-5)


def test_per_shift_leg_and_vehicle_figures(scenario):
    stats = event_statistics(scenario.event)
    s1, s2 = scenario.shifts
    assert stats.by_shift[s1.id].auto_distance == approx(5 * STEP_M)
    assert stats.by_shift[s2.id].auto_distance == approx(8 * STEP_M)
    assert stats.by_shift[s2.id].interventions == 1
    assert stats.by_shift[s1.id].mdbi.upper == pytest.approx(2 * 5 * STEP_M / CHI2_05[2], rel=1e-5)
    assert stats.by_vehicle[s1.vehicle_id].auto_seconds == 340
    assert stats.by_vehicle[s2.vehicle_id].auto_seconds == 600
    (leg1,) = s1.legs.all()
    assert stats.by_leg[leg1.id].manual_distance == approx(STEP_M)


def test_zero_interventions_is_censored_with_a_lower_bound_only():
    estimate = poisson_estimate(1000.0, 0)
    assert estimate.censored and estimate.value is None and estimate.upper is None
    assert estimate.lower == pytest.approx(2000.0 / CHI2_95[2], rel=1e-5)


def test_open_segments_make_the_figures_provisional(open_scenario):
    overall = event_statistics(open_scenario).overall
    assert overall.provisional
    # The open AUTO run lasts until its newest pose (T0+90 s), from T0+60 s.
    assert overall.auto_seconds == 30
    assert overall.interventions == 1


def test_event_without_poses_still_has_times_and_joins(scenario):
    from telemetry.models import Pose
    from telemetry.services.segment_figures import measure_figures

    masters = list(Pose.objects.values_list("segment_id", flat=True).distinct())
    Pose.objects.all().delete()
    # A raw delete passes by the figures stored at write time: measure them again.
    measure_figures(masters)
    overall = event_statistics(scenario.event).overall
    assert overall.auto_seconds == T_A
    # Only straight joins between start positions remain: A1 0->.003, A2 none, ...
    assert overall.auto_distance == approx((3 + 0 + 4 + 4) * STEP_M)


def test_the_robots_suggested_reason_counts_only_when_confirmed_or_by_setting(scenario, settings):
    from events.models import Segment

    # I3's take-over as the collector stores it: Unassigned, the robot suggesting Safety.
    Segment.objects.filter(parent=scenario.masters["I3"]).update(
        ito_reason="unassigned", suggested_reason="safety"
    )
    by_reason = event_statistics(scenario.event).overall.interventions_by_reason
    assert by_reason.get("safety") == 1 and by_reason.get("unassigned") == 1
    settings.FTT_COUNT_ROBOT_REASONS = True
    by_reason = event_statistics(scenario.event).overall.interventions_by_reason
    assert by_reason.get("safety") == 2 and "unassigned" not in by_reason


def test_runs_come_in_driving_order_when_a_later_made_shift_started_first(
    vehicle, other_vehicle, performer
):
    event = logs.create_test_event(location="Order", at=T0)
    # The later shift is entered first: ids follow entry, not time.
    late = logs.create_shift(test_event=event, vehicle=other_vehicle, performer=performer, at=T1)
    late_leg = logs.create_leg(shift=late, at=T1)
    late_runs = [_switch(late_leg, "auto", T1, 0, 0.003), _switch(late_leg, "ito", T1, 30, 0.004)]
    early = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    first_leg = logs.create_leg(shift=early, at=T0)
    early_runs = [_switch(first_leg, "auto", T0, 0, 0.0), _switch(first_leg, "ito", T0, 60, 0.001)]
    second_leg = logs.create_leg(shift=early, at=T0 + (T1 - T0) / 2)
    early_runs.append(_switch(second_leg, "auto", T0, 1900, 0.002))
    expected = [m.pk for m in early_runs + late_runs]
    assert [run.id for run in event_runs(event, tracks=False)] == expected
    assert [run.id for run in campaign_runs([event])[event.pk]] == expected
