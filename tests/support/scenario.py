"""A synthetic test event whose every figure can be worked out by hand.

All positions lie on the equator, where the WGS84 geodesic between two points
is an arc of the equator: length = a * dlon (a = 6 378 137 m, dlon in radians).
Positions are multiples of STEP degrees of longitude, so each distance below
is a whole number of steps.

Shift 1 (vehicle husky, Tokyo time, leg weather sunny), from T0:
  A1 AUTO  T0+0   .. T0+100  lon 0.000 -> poses .0005 .. .002 -> next start .003  3 steps
  I1 ITO   T0+100 .. T0+160  lon 0.003 -> pose .0035 -> next start .004            1 step
         reasons: safety T0+100..T0+160 (60 s), planner T0+120..T0+160 (40 s)
  A2 AUTO  T0+160 .. T0+400  lon 0.004 -> poses .005 .006 (last master)            2 steps
Shift 2 (vehicle jackal, leg weather rain), from T1 = T0 + 1 h:
  A3 AUTO  T1+0   .. T1+300  lon 0.010 -> poses .011 .012 .013 (20 s gap) -> .014  4 steps
  I2 ITO   T1+300 .. T1+330  lon 0.014, no poses -> next start .016               2 steps
         reason: goal (does not count as an intervention)
  A4 AUTO  T1+330 .. T1+630  lon 0.016 -> poses .017 .018 .019 -> next .020        4 steps
  I3 ITO   T1+630 .. T1+700  lon 0.020 -> pose .021                               1 step
         reason: unexpected (counts)
"""

import math
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from events.models import Personnel
from events.services import logs, notes, segments
from events.services.segments import GpsPosition
from telemetry.services import attachments, pose_writes
from telemetry.services.pose_writes import GpsFix
from tests.support.images import png

STEP = 0.001
STEP_M = 6378137.0 * math.radians(STEP)
T0 = datetime(2026, 3, 2, 1, 0, tzinfo=UTC)  # 10:00 in Tokyo
T1 = T0 + timedelta(hours=1)


def chi2_quantile_even(p: float, dof: int) -> float:
    """chi-square quantile for an even number of degrees of freedom, by bisection on
    the closed-form CDF 1 - exp(-x/2) * sum_{j<dof/2} (x/2)^j / j!  (independent of scipy)."""

    def cdf(x):
        half = x / 2
        return 1 - math.exp(-half) * sum(half**j / math.factorial(j) for j in range(dof // 2))

    lo, hi = 0.0, 200.0
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return (lo + hi) / 2


CHI2_95 = {dof: chi2_quantile_even(0.95, dof) for dof in (2, 4, 6)}
CHI2_05 = {dof: chi2_quantile_even(0.05, dof) for dof in (2, 4)}

HOSTILE = 'Zürich 東京 ✓ <b>&_#*$\\ %{} `x` @ref [link] "q" #set page(width: 1pt)'


@dataclass
class Scenario:
    event: object
    shifts: list
    masters: dict  # name -> master Segment
    people: dict


def _at(base, seconds):
    return base + timedelta(seconds=seconds)


def _fixes(base, points):
    return [GpsFix(longitude=lon, latitude=0.0, robot_stamp=_at(base, t)) for t, lon in points]


def _switch(leg, mode, base, t, lon, reason="unassigned", uncertainty=None):
    return segments.report_mode(
        leg,
        mode,
        at=_at(base, t),
        gps=GpsPosition(lon, 0.0),
        reason=reason,
        start_uncertainty=uncertainty,
    ).master


def build_scenario(vehicle, other_vehicle, performer, text=HOSTILE) -> Scenario:
    people = {
        role: Personnel.objects.create(name=f"{label} {text}", institution=text)
        for role, label in (
            ("director", "Director"),
            ("admin", "Admin"),
            ("safety", "Safety"),
            ("operator", "Operator"),
        )
    }
    roles = dict(
        test_director=people["director"],
        test_administrator=people["admin"],
        safety_officer=people["safety"],
        robot_operator=people["operator"],
    )
    event = logs.create_test_event(
        location=f"Field {text}", version=text, time_zone="Asia/Tokyo", note=text, at=T0
    )
    s1 = logs.create_shift(
        test_event=event,
        vehicle=vehicle,
        performer=performer,
        at=T0,
        test_intent=text,
        note=text,
        **roles,
    )
    leg1 = logs.create_leg(shift=s1, at=T0, weather_id="sunny", note=text)
    m = {}
    m["A1"] = _switch(leg1, "auto", T0, 0, 0.000)
    a1_poses = [(5, 0.0005), (10, 0.001), (15, 0.0015), (20, 0.002)]
    pose_writes.store_poses(m["A1"], _fixes(T0, a1_poses))
    m["I1"] = _switch(leg1, "ito", T0, 100, 0.003, reason="safety")
    segments.annotate_segment(m["I1"].children.get(), obstacle=text, lighting=text, slope=text)
    segments.add_ito_child(m["I1"], reason="planner", at=_at(T0, 120))
    pose_writes.store_poses(m["I1"], _fixes(T0, [(110, 0.0035)]))
    notes.add_note(m["I1"], text=f"note {text}", author=people["operator"])
    attachments.attach_image(m["I1"], content=png((64, 48), (40, 120, 200)), description=text)
    m["A2"] = _switch(leg1, "auto", T0, 160, 0.004)
    pose_writes.store_poses(m["A2"], _fixes(T0, [(170, 0.005), (180, 0.006)]))
    logs.close_leg(leg1, at=_at(T0, 400))
    logs.close_shift(s1, at=_at(T0, 400))

    s2 = logs.create_shift(
        test_event=event, vehicle=other_vehicle, performer=performer, at=T1, **roles
    )
    leg2 = logs.create_leg(shift=s2, at=T1, weather_id="rainy")
    m["A3"] = _switch(leg2, "auto", T1, 0, 0.010)
    pose_writes.store_poses(m["A3"], _fixes(T1, [(10, 0.011), (20, 0.012), (40, 0.013)]))
    m["I2"] = _switch(leg2, "ito", T1, 300, 0.014, reason="goal")
    # A robot whose mode message has no stamp: it switched up to 0.8 s earlier.
    m["A4"] = _switch(leg2, "auto", T1, 330, 0.016, uncertainty=0.8)
    pose_writes.store_poses(m["A4"], _fixes(T1, [(340, 0.017), (350, 0.018), (360, 0.019)]))
    m["I3"] = _switch(leg2, "ito", T1, 630, 0.020, reason="unexpected")
    pose_writes.store_poses(m["I3"], _fixes(T1, [(640, 0.021)]))
    logs.count_missed_fixes(leg2.pk, 12)  # as the robot's collector estimated
    logs.close_leg(leg2, at=_at(T1, 700))
    logs.close_shift(s2, at=_at(T1, 700))
    for seg in m.values():
        seg.refresh_from_db()
    return Scenario(event=event, shifts=[s1, s2], masters=m, people=people)


def build_open_scenario(vehicle, performer):
    """A test event still running: its last AUTO master is open."""
    event = logs.create_test_event(location="läuft noch", time_zone="Europe/Berlin", at=T0)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    leg = logs.create_leg(shift=shift, at=T0)
    _switch(leg, "ito", T0, 0, 0.0, reason="safety")
    auto = _switch(leg, "auto", T0, 60, 0.001)
    pose_writes.store_poses(auto, _fixes(T0, [(70, 0.002), (90, 0.003)]))
    return event
