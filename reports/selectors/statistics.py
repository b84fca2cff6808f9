"""Reliability statistics of a test event, per leg, shift, vehicle and overall.

Everything the report, the GUI and the API show as a figure comes from here.

Definitions (also printed in the report's methods appendix, see ``reports.selectors.formulas``):

* A *run* is a master segment: one continuous stretch in one mode (AUTO, ITO,
  or UNKNOWN: logged before the robot said its mode; counted in the totals only).
* Duration of a run = end - start (server clock).  An open run (no end yet)
  lasts until the latest thing known about it: its newest pose or reason.
  Statistics over open runs are *provisional*.
* Distance of a run: see :mod:`telemetry.selectors.distances` (start
  position + poses + next start).  A run without poses contributes the
  straight join from its start to the next start, if both are known, and is
  listed as a data gap.
* An *intervention* is an ITO master with at least one reason (child) whose
  catalogue entry ``counts_as_intervention`` (for a final event: as frozen at
  finalisation, ``events.selectors.taxonomy``).  A master with several counted
  reasons is one intervention overall and one under each of its reasons.
* Exposure: autonomous distance D_a and autonomous time T_a (sums over AUTO runs).
  I = number of interventions.
* Autonomy ratio by distance = D_a / (D_a + D_m); by time = T_a / (T_a + T_m),
  where D_m, T_m sum over all ITO runs, counted or not (the share of the test
  the vehicle drove itself).
* MDBI = D_a / I, MTBI = T_a / I.  Two-sided 90 % confidence bounds assume a
  homogeneous Poisson process observed over a fixed exposure E:
  lower = 2E / chi2(0.95; 2I + 2), upper = 2E / chi2(0.05; 2I) (infinite for I = 0).
  With I = 0 there is no point estimate: the value is reported as ">= E".
* Interventions per km = I / (D_a / 1000); per hour = I / (T_a / 3600).
* Manual time per reason = sum of the durations of the reasons (children)
  with that key; children of one master may overlap.
"""

from collections import defaultdict
from dataclasses import asdict, dataclass, field
from datetime import datetime
from typing import NamedTuple

import numpy as np
from django.conf import settings
from scipy.stats import chi2

from common import cyclic_gc
from events.models import ItoReason, Leg, Segment, SegmentType, TestEvent
from events.selectors.labels import segment_labels
from events.selectors.taxonomy import counted_reasons, counted_reasons_of
from reports.selectors.formulas import FORMULAS, keyed
from telemetry.selectors.distances import measured_paths, stored_paths
from telemetry.selectors.tracks import Track
from telemetry.storage import plain_rows
from telemetry.storage.keys import GPS_TRACK

CONFIDENCE = 0.90

# The path of a run read without its track, shared by all of them (read-only).
_NO_PATH = np.empty(0)
_NO_PATH.flags.writeable = False


@dataclass(slots=True)
class ReasonSpan:
    id: int
    reason: str
    start: datetime
    end: datetime
    is_open: bool
    obstacle: str = ""
    lighting: str = ""
    slope: str = ""

    @property
    def seconds(self) -> float:
        return (self.end - self.start).total_seconds()


@dataclass(slots=True)
class Run:
    """One master segment with what the statistics need to know about it."""

    id: int
    kind: str
    leg_id: int
    shift_id: int
    vehicle_id: int
    start: datetime
    end: datetime
    is_open: bool
    distance: float
    pose_count: int
    reasons: list[ReasonSpan] = field(default_factory=list)
    counted_reasons: list[str] = field(default_factory=list)
    track: Track | None = None
    has_start_position: bool = False
    # The polyline the distance was measured on, joins included.
    path_x: np.ndarray = field(default_factory=lambda: _NO_PATH)
    path_y: np.ndarray = field(default_factory=lambda: _NO_PATH)
    # The path's first point (where a take-over happened), None when unknown.
    origin: tuple[float, float] | None = None
    # The GUI's name of the segment ("Leg 2 · #7"), see events.selectors.labels.
    label: str = ""
    # Seconds the robot may have switched before `start` (a mode message without a stamp).
    start_uncertainty: float | None = None

    @property
    def seconds(self) -> float:
        return (self.end - self.start).total_seconds()

    @property
    def is_intervention(self) -> bool:
        return bool(self.counted_reasons)


@dataclass
class Estimate:
    """Exposure per intervention with its confidence bounds.

    ``value`` is None when there were no interventions (censored: ">= exposure").
    ``upper`` is None when unbounded.
    """

    exposure: float
    count: int
    value: float | None
    lower: float | None
    upper: float | None
    censored: bool


def poisson_estimate(exposure: float, count: int, confidence: float = CONFIDENCE) -> Estimate:
    """Exposure / count with exact two-sided chi-square bounds (see module docstring)."""
    alpha = 1.0 - confidence
    if exposure <= 0:
        return Estimate(exposure, count, None, None, None, count == 0)
    lower = 2.0 * exposure / chi2.ppf(1.0 - alpha / 2.0, 2 * count + 2)
    if count == 0:
        return Estimate(exposure, 0, None, float(lower), None, True)
    upper = 2.0 * exposure / chi2.ppf(alpha / 2.0, 2 * count)
    return Estimate(exposure, count, exposure / count, float(lower), float(upper), False)


def _ratio(part: float, whole: float) -> float | None:
    return part / whole if whole > 0 else None


@dataclass
class Figures:
    auto_runs: int
    ito_runs: int
    auto_seconds: float
    manual_seconds: float
    auto_distance: float
    manual_distance: float
    unknown_seconds: float
    unknown_distance: float
    autonomy_ratio_distance: float | None
    autonomy_ratio_time: float | None
    interventions: int
    interventions_by_reason: dict[str, int]
    manual_seconds_by_reason: dict[str, float]
    mean_auto_run: float | None
    max_auto_run: float | None
    longest_without_intervention: float
    mdbi: Estimate
    mtbi: Estimate
    interventions_per_km: float | None
    interventions_per_hour: float | None
    provisional: bool

    @property
    def total_distance(self) -> float:
        return self.auto_distance + self.manual_distance + self.unknown_distance

    @property
    def total_seconds(self) -> float:
        return self.auto_seconds + self.manual_seconds + self.unknown_seconds

    def as_dict(self) -> dict:
        data = asdict(self)
        data["total_distance"] = self.total_distance
        data["total_seconds"] = self.total_seconds
        return data


def figures(runs: list[Run]) -> Figures:
    """Aggregate runs of any grouping (leg, shift, vehicle, event) into figures."""
    auto = [r for r in runs if r.kind == SegmentType.AUTO]
    ito = [r for r in runs if r.kind == SegmentType.ITO]
    unknown = [r for r in runs if r.kind == SegmentType.UNKNOWN]
    d_a = sum(r.distance for r in auto)
    d_m = sum(r.distance for r in ito)
    t_a = sum(r.seconds for r in auto)
    t_m = sum(r.seconds for r in ito)
    count = sum(1 for r in ito if r.is_intervention)
    by_reason: dict[str, int] = defaultdict(int)
    time_by_reason: dict[str, float] = defaultdict(float)
    for run in ito:
        for key in set(run.counted_reasons):
            by_reason[key] += 1
        for span in run.reasons:
            time_by_reason[span.reason] += span.seconds
    return Figures(
        auto_runs=len(auto),
        ito_runs=len(ito),
        auto_seconds=t_a,
        manual_seconds=t_m,
        auto_distance=d_a,
        manual_distance=d_m,
        unknown_seconds=sum(r.seconds for r in unknown),
        unknown_distance=sum(r.distance for r in unknown),
        autonomy_ratio_distance=_ratio(d_a, d_a + d_m),
        autonomy_ratio_time=_ratio(t_a, t_a + t_m),
        interventions=count,
        interventions_by_reason=dict(sorted(by_reason.items(), key=lambda kv: (-kv[1], kv[0]))),
        manual_seconds_by_reason=dict(sorted(time_by_reason.items())),
        mean_auto_run=d_a / len(auto) if auto else None,
        max_auto_run=max((r.distance for r in auto), default=None),
        longest_without_intervention=_longest_without_intervention(runs),
        mdbi=poisson_estimate(d_a, count),
        mtbi=poisson_estimate(t_a, count),
        interventions_per_km=count / (d_a / 1000.0) if d_a > 0 else None,
        interventions_per_hour=count / (t_a / 3600.0) if t_a > 0 else None,
        provisional=any(r.is_open or any(s.is_open for s in r.reasons) for r in runs),
    )


def _longest_without_intervention(runs: list[Run]) -> float:
    """Runs in driving order; the stretch restarts at each intervention and each leg."""
    longest = stretch = 0.0
    leg = None
    for run in runs:
        if run.leg_id != leg or run.is_intervention:
            stretch, leg = 0.0, run.leg_id
        if run.kind == SegmentType.AUTO:
            stretch += run.distance
            longest = max(longest, stretch)
    return longest


class SegmentRow(NamedTuple):
    """The columns of a segment a run needs, as one row: no model instance, as
    a campaign's comparison reads every segment.  Start positions are not
    among them: ``distances.start_points`` reads them by leg."""

    pk: int
    parent_id: int | None
    segment_type_id: str
    ito_reason_id: str | None
    suggested_reason_id: str | None
    start: datetime
    start_uncertainty: float | None
    end: datetime | None
    obstacle: str
    lighting: str
    slope: str
    start_local_x: float | None
    start_local_y: float | None
    leg_id: int
    shift_id: int
    vehicle_id: int
    test_event_id: int


# The ORM path of each SegmentRow column, in its order.
_ROW_COLUMNS = (
    *("id", "parent", "segment_type", "ito_reason", "suggested_reason", "start"),
    *("start_uncertainty", "end", "obstacle", "lighting", "slope", "start_local_x"),
    *("start_local_y", "leg", "leg__shift", "leg__shift__vehicle", "leg__shift__test_event"),
)


def _effective_end(segment: SegmentRow, last_stamp: datetime | None, children: list[SegmentRow]):
    if segment.end is not None:
        return segment.end
    known = [segment.start]
    if last_stamp is not None:
        known.append(last_stamp)
    for child in children:
        known.append(child.end or child.start)
    return max(known)


def counted_reason(child: SegmentRow) -> str:
    """The reason statistics count: the operator's; the robot's suggestion only
    for a take-over still Unassigned and with settings.FTT_COUNT_ROBOT_REASONS."""
    if Segment.reason_unassigned(child.ito_reason_id):
        if settings.FTT_COUNT_ROBOT_REASONS and child.suggested_reason_id:
            return child.suggested_reason_id
        return ItoReason.UNASSIGNED
    return child.ito_reason_id


def segment_scope(
    event: TestEvent,
    *,
    shift: int | None = None,
    leg: int | None = None,
    legs: list[int] | None = None,
    via: str = "",
) -> dict:
    """The ORM filter of a test event's segments, narrowed to one shift, one leg
    or some legs (ids); ``via`` is the path to the segment, e.g. ``"segment__"``."""
    found = {f"{via}leg__shift__test_event": event}
    if shift is not None:
        found[f"{via}leg__shift_id"] = shift
    if leg is not None:
        found[f"{via}leg_id"] = leg
    if legs is not None:
        found[f"{via}leg_id__in"] = legs
    return found


def event_runs(
    event: TestEvent,
    mode: str = GPS_TRACK,
    *,
    tracks: bool = True,
    shift: int | None = None,
    leg: int | None = None,
    legs: list[int] | None = None,
) -> list[Run]:
    """All master segments of a test event as runs, ordered by leg and time;
    ``shift``, ``leg`` or ``legs`` (ids) narrow them to one shift, one leg or
    some legs (``campaign_runs`` of this one event)."""
    scope = segment_scope(event, shift=shift, leg=leg, legs=legs)
    return _runs(scope, [event], mode, tracks).get(event.pk, [])


@cyclic_gc.paused()
def campaign_runs(events: list[TestEvent], mode: str = GPS_TRACK) -> dict[int, list[Run]]:
    """{test event id: ``event_runs`` of it, without tracks} for many test events
    in their given order, read with one query per table, not one per event."""
    found = _runs({"leg__shift__test_event__in": events}, events, mode, tracks=False)
    return {event.pk: found.get(event.pk, []) for event in events}


def _driving_order(scope: dict) -> list[SegmentRow]:
    """The segments in ``scope`` by shift (start, id), leg (start, id), then their
    own start and id.  The database orders each leg's rows; the legs, a few
    hundred rows, are ordered by a query of their own, which costs less than
    sorting every segment by six columns of three tables."""
    rows = plain_rows(
        Segment.objects.filter(**scope).order_by("leg_id", "start", "id").values_list(*_ROW_COLUMNS)
    )
    by_leg: dict[int, list[SegmentRow]] = defaultdict(list)
    for row in rows:
        segment = SegmentRow._make(row)
        by_leg[segment.leg_id].append(segment)
    legs = Leg.objects.filter(pk__in=by_leg).order_by("shift__start", "shift_id", "start", "id")
    return [segment for leg in legs.values_list("id", flat=True) for segment in by_leg[leg]]


def _runs(scope: dict, events: list[TestEvent], mode: str, tracks: bool) -> dict[int, list[Run]]:
    """The runs of the segments in ``scope`` by test event.  Distances, pose
    counts and the end of an open segment come from the figures stored at write
    time; only ``tracks`` (for drawing and the exports) reads the poses."""
    segments = _driving_order(scope)
    counted = counted_reasons_of(events)
    masters = [s for s in segments if s.parent_id is None]
    children: dict[int, list[SegmentRow]] = defaultdict(list)
    for s in segments:
        if s.parent_id is not None:
            children[s.parent_id].append(s)
    kept = stored_paths(masters, mode)
    paths = measured_paths(masters, mode) if tracks else {}
    # Only the masters are labelled: each is numbered among its leg's masters all the same.
    labels = segment_labels(Segment.objects.filter(**scope, parent=None))

    runs: dict[int, list[Run]] = defaultdict(list)
    for master in masters:
        path = paths.get(master.pk)
        figures = kept[master.pk]
        kids = children.get(master.pk, ())
        end = _effective_end(master, figures.last_stamp, kids)
        spans = [_reason_span(c, end) for c in kids]
        counted_here = counted[master.test_event_id]
        runs[master.test_event_id].append(
            Run(
                id=master.pk,
                kind=master.segment_type_id,
                leg_id=master.leg_id,
                shift_id=master.shift_id,
                vehicle_id=master.vehicle_id,
                start=master.start,
                end=end,
                is_open=master.end is None,
                distance=figures.distance or 0.0,
                pose_count=figures.points,
                reasons=spans,
                counted_reasons=[s.reason for s in spans if s.reason in counted_here],
                track=path and path.track,
                has_start_position=figures.has_start_position,
                path_x=path.x if path else _NO_PATH,
                path_y=path.y if path else _NO_PATH,
                origin=figures.origin,
                label=labels[master.pk],
                start_uncertainty=master.start_uncertainty,
            )
        )
    return runs


def _reason_span(child: SegmentRow, master_end: datetime) -> ReasonSpan:
    return ReasonSpan(
        id=child.pk,
        reason=counted_reason(child),
        start=child.start,
        end=child.end or max(master_end, child.start),
        is_open=child.end is None,
        obstacle=child.obstacle,
        lighting=child.lighting,
        slope=child.slope,
    )


@dataclass
class EventStatistics:
    test_event_id: int
    mode: str
    overall: Figures
    by_shift: dict[int, Figures]
    by_leg: dict[int, Figures]
    by_vehicle: dict[int, Figures]
    counted_reasons: list[str]
    runs: list[Run]

    @property
    def provisional(self) -> bool:
        return self.overall.provisional

    def runs_by_shift(self) -> dict[int, list[Run]]:
        groups: dict[int, list[Run]] = defaultdict(list)
        for run in self.runs:
            groups[run.shift_id].append(run)
        return groups

    def as_dict(self) -> dict:
        """Plain JSON-ready figures (seconds and metres), as the API returns them."""
        return {
            "test_event": self.test_event_id,
            "mode": self.mode,
            "confidence": CONFIDENCE,
            "provisional": self.provisional,
            "counted_reasons": self.counted_reasons,
            "formulas": keyed(FORMULAS),
            "overall": self.overall.as_dict(),
            "shifts": {str(k): v.as_dict() for k, v in self.by_shift.items()},
            "legs": {str(k): v.as_dict() for k, v in self.by_leg.items()},
            "vehicles": {str(k): v.as_dict() for k, v in self.by_vehicle.items()},
            "segments": [
                {
                    "id": run.id,
                    "label": run.label,
                    "type": run.kind,
                    "shift": run.shift_id,
                    "leg": run.leg_id,
                    "distance": run.distance,
                    "seconds": run.seconds,
                    "intervention": run.is_intervention,
                }
                for run in self.runs
            ],
        }


def _grouped(runs: list[Run], key) -> dict[int, Figures]:
    groups: dict[int, list[Run]] = defaultdict(list)
    for run in runs:
        groups[key(run)].append(run)
    return {k: figures(v) for k, v in groups.items()}


def event_statistics(
    event: TestEvent,
    mode: str = GPS_TRACK,
    runs: list[Run] | None = None,
    *,
    tracks: bool = False,
    shift: int | None = None,
    leg: int | None = None,
) -> EventStatistics:
    """Figures for the whole test event, or only its ``shift`` or ``leg`` (ids),
    and each leg, shift and vehicle in it (``tracks``: with each run's track,
    for the report's drawings)."""
    if runs is None:
        runs = event_runs(event, mode, tracks=tracks, shift=shift, leg=leg)
    return EventStatistics(
        test_event_id=event.pk,
        mode=mode,
        overall=figures(runs),
        by_shift=_grouped(runs, lambda r: r.shift_id),
        by_leg=_grouped(runs, lambda r: r.leg_id),
        by_vehicle=_grouped(runs, lambda r: r.vehicle_id),
        counted_reasons=sorted(counted_reasons(event)),
        runs=runs,
    )
