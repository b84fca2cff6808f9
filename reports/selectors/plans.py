"""Did we do what the test plan said: each test case's criteria judged on the
statistics' own figures (reports.selectors.statistics), per leg and per case.

Verdicts: "pass", "fail", "not yet" (the leg or case is still open and the
figure can still change), and "needs a judgement" for a criterion a person
decides.  A case's own verdicts use the figures of all its legs together (the
longest distance without intervention restarts with each leg, so it is the best
run's); "runs completed" counts its closed legs.  A criterion met while its leg
is still open passes at once where more driving cannot undo it (a distance
reached), and fails at once where more driving cannot repair it (a forbidden
reason occurred).
"""

import io
from dataclasses import dataclass, field

from django.utils.translation import gettext as _

from common.spreadsheet import SafeWriter
from events.models import Criterion, Judgement, Leg, TestCase, TestEvent
from reports.selectors.statistics import Figures, Run, event_runs, figures
from telemetry.storage.keys import GPS_TRACK

PASS, FAIL, NOT_YET, JUDGE = "pass", "fail", "not yet", "needs a judgement"
Kind = Criterion.Kind


@dataclass
class Verdict:
    criterion: Criterion
    measured: float | list[str] | None
    verdict: str
    note: str = ""

    def as_dict(self) -> dict:
        return {
            "criterion": self.criterion.pk,
            "kind": self.criterion.kind,
            "text": str(self.criterion),
            "threshold": self.criterion.value,
            "measured": self.measured,
            "verdict": self.verdict,
            "note": self.note,
        }


@dataclass
class LegResult:
    leg: Leg
    is_open: bool
    figures: Figures
    verdicts: list[Verdict]

    def as_dict(self) -> dict:
        return {
            "leg": self.leg.pk,
            "label": f"Shift {self.leg.shift.number} · Leg {self.leg.number}",
            "open": self.is_open,
            "verdicts": [v.as_dict() for v in self.verdicts],
        }


@dataclass
class CaseResult:
    case: TestCase
    legs: list[LegResult]
    runs_done: int
    verdicts: list[Verdict]
    progress: str = ""
    figures: Figures | None = field(default=None, repr=False)

    @property
    def verdict(self) -> str:
        found = {v.verdict for v in self.verdicts}
        for outcome in (FAIL, JUDGE, NOT_YET):
            if outcome in found:
                return outcome
        return PASS

    def as_dict(self) -> dict:
        return {
            "test_case": self.case.pk,
            "key": self.case.key,
            "title": self.case.title,
            "planned_runs": self.case.planned_runs,
            "runs_done": self.runs_done,
            "progress": self.progress,
            "verdict": self.verdict,
            "verdicts": [v.as_dict() for v in self.verdicts],
            "legs": [leg.as_dict() for leg in self.legs],
        }


@dataclass
class PlanResult:
    test_event: TestEvent
    cases: list[CaseResult]
    unplanned_legs: list[Leg]

    def as_dict(self) -> dict:
        return {
            "test_event": self.test_event.pk,
            "cases": [c.as_dict() for c in self.cases],
            "unplanned_legs": [leg.pk for leg in self.unplanned_legs],
        }


def test_plan(event: TestEvent, mode: str = GPS_TRACK, runs: list[Run] | None = None) -> PlanResult:
    """Every test case of the event with its legs' and its own verdicts."""
    runs = event_runs(event, mode) if runs is None else runs
    by_leg: dict[int, list[Run]] = {}
    for run in runs:
        by_leg.setdefault(run.leg_id, []).append(run)
    legs = list(
        Leg.objects.filter(shift__test_event=event).select_related("shift").order_by("start", "id")
    )
    judgements = {
        (j.criterion_id, j.leg_id): j
        for j in Judgement.objects.filter(criterion__test_case__test_event=event)
    }
    cases = []
    for case in event.test_cases.prefetch_related("criteria__reasons"):
        own = [leg for leg in legs if leg.test_case_id == case.pk]
        criteria = list(case.criteria.all())
        results = []
        for leg in own:
            leg_figures = figures(by_leg.get(leg.pk, []))
            open_ = leg.end is None
            verdicts = [
                _judge(c, leg_figures, open_, judgements.get((c.pk, leg.pk)))
                for c in criteria
                if c.kind in Criterion.PER_LEG or c.kind == Kind.JUDGED
            ]
            results.append(LegResult(leg, open_, leg_figures, verdicts))
        case_runs = [run for leg in own for run in by_leg.get(leg.pk, [])]
        case_figures = figures(case_runs)
        done = sum(1 for r in results if not r.is_open)
        # A case is still being driven while a leg of it is open, or while the test
        # event is open and fewer runs than planned are done.
        case_open = any(r.is_open for r in results) or (
            event.end is None and done < case.planned_runs
        )
        verdicts = []
        for criterion in criteria:
            if criterion.kind == Kind.RUNS_COMPLETED:
                verdicts.append(_runs_completed(criterion, done, case_open))
            else:
                judgement = judgements.get((criterion.pk, None))
                verdicts.append(_judge(criterion, case_figures, case_open, judgement))
        result = CaseResult(case, results, done, verdicts, figures=case_figures)
        result.progress = _progress(case, result, criteria)
        cases.append(result)
    return PlanResult(event, cases, [leg for leg in legs if leg.test_case_id is None])


def _without_threshold(criterion: Criterion) -> Verdict:
    # Nothing to compare with: a person looks at it (and sets the value in admin).
    return Verdict(criterion, None, JUDGE, _("no threshold set"))


def _judge(criterion: Criterion, f: Figures, is_open: bool, judgement: Judgement | None):
    kind, value = criterion.kind, criterion.value
    if criterion.lacks_threshold:
        return _without_threshold(criterion)
    if kind == Kind.JUDGED:
        if judgement is None:
            return Verdict(criterion, None, JUDGE)
        return Verdict(criterion, None, PASS if judgement.passed else FAIL, judgement.note)
    if kind == Kind.FORBIDDEN_REASONS:
        forbidden = {r.key for r in criterion.reasons.all()}
        occurred = sorted(forbidden & set(f.manual_seconds_by_reason))
        if occurred:
            return Verdict(criterion, occurred, FAIL)
        return Verdict(criterion, [], NOT_YET if is_open else PASS)
    if kind == Kind.DISTANCE_WITHOUT_INTERVENTION:
        measured = f.longest_without_intervention
        return Verdict(
            criterion, measured, _at_least(measured, value, is_open, final_once_met=True)
        )
    if kind == Kind.INTERVENTIONS_PER_KM:
        measured = f.interventions_per_km
        if measured is None:
            return Verdict(
                criterion, None, NOT_YET if is_open else FAIL, _("no autonomous distance")
            )
        return Verdict(criterion, measured, _open_or(measured <= value, is_open))
    if kind == Kind.AUTO_TIME_SHARE:
        share = f.autonomy_ratio_time
        measured = None if share is None else 100.0 * share
        if measured is None:
            return Verdict(criterion, None, NOT_YET if is_open else FAIL, _("no driving time"))
        return Verdict(criterion, measured, _open_or(measured >= value, is_open))
    raise ValueError(f"criterion kind {kind} is judged per case")


def _runs_completed(criterion: Criterion, done: int, is_open: bool) -> Verdict:
    if criterion.lacks_threshold:
        return _without_threshold(criterion)
    return Verdict(criterion, float(done), _at_least(done, criterion.value, is_open, True))


def _at_least(measured, value, is_open: bool, final_once_met: bool) -> str:
    if measured >= value and (final_once_met or not is_open):
        return PASS
    return NOT_YET if is_open else FAIL


def _open_or(met: bool, is_open: bool) -> str:
    if is_open:
        return NOT_YET
    return PASS if met else FAIL


def _progress(case: TestCase, result: CaseResult, criteria: list[Criterion]) -> str:
    """What the cockpit shows while a case is driven: "run 2 of 3 · 312 m of 500 m …"."""
    current = next((r for r in result.legs if r.is_open), None)
    number = result.runs_done + (1 if current else 0)
    parts = [
        _("run %(number)s of %(planned)s")
        % {"number": max(number, 1), "planned": case.planned_runs}
    ]
    # The run being driven, else the best run of the case.
    shown = current.figures if current else result.figures
    for criterion in criteria:
        distance = criterion.kind == Kind.DISTANCE_WITHOUT_INTERVENTION
        if distance and shown is not None and not criterion.lacks_threshold:
            reached = shown.longest_without_intervention
            parts.append(
                _("%(reached)s m of %(target)s m without intervention")
                % {"reached": f"{reached:.0f}", "target": f"{criterion.value:.0f}"}
            )
    return " · ".join(parts)


CSV_COLUMNS = (
    "test_case",
    "title",
    "scope",
    "criterion",
    "threshold",
    "measured",
    "verdict",
    "note",
)


def test_plan_csv(plan: PlanResult) -> str:
    """One row per verdict: each case's own verdicts, then each of its legs'."""
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(CSV_COLUMNS)
    for case in plan.cases:
        scoped = [("case", v) for v in case.verdicts]
        for leg in case.legs:
            scope = leg.as_dict()["label"]
            scoped += [(scope, v) for v in leg.verdicts]
        for scope, v in scoped:
            measured = ", ".join(v.measured) if isinstance(v.measured, list) else v.measured
            row = [case.case.key, case.case.title, scope, str(v.criterion), v.criterion.value]
            writer.writerow([*row, measured, v.verdict, v.note])
    return out.getvalue()
