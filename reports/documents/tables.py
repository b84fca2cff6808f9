"""The report's tables: rows of labels and formatted figures."""

from django.utils.translation import gettext as _

from reports import formatting as fmt
from reports.selectors.plans import FAIL, JUDGE, NOT_YET, PASS
from reports.selectors.statistics import CONFIDENCE, Figures


def label_rows(pairs) -> list[list[str]]:
    return [[label, value] for label, value in pairs]


def person_text(person) -> str:
    if person is None:
        return fmt.DASH
    return f"{person.name} ({person.institution})" if person.institution else person.name


def weather_text(legs) -> str:
    """The weather of a shift's legs in time order, a repeat named once."""
    names = []
    for leg in legs:
        label = leg.weather.shown_short if leg.weather else _("unknown")
        if not names or names[-1] != label:
            names.append(label)
    return ", ".join(names) or _("unknown")


def figure_rows(f: Figures) -> list:
    conf = f"{round(CONFIDENCE * 100)} %"
    return label_rows(
        [
            (_("Total distance"), fmt.metres(f.total_distance)),
            (_("Autonomous distance"), fmt.metres(f.auto_distance)),
            (_("Manual (ITO) distance"), fmt.metres(f.manual_distance)),
            (_("Autonomy by distance"), fmt.percent(f.autonomy_ratio_distance)),
            (_("Autonomous time"), fmt.duration(f.auto_seconds)),
            (_("Manual (ITO) time"), fmt.duration(f.manual_seconds)),
            (_("Autonomy by time"), fmt.percent(f.autonomy_ratio_time)),
            (_("Autonomous runs"), str(f.auto_runs)),
            (_("Mean autonomous run"), fmt.metres(f.mean_auto_run)),
            (_("Longest autonomous run"), fmt.metres(f.max_auto_run)),
            (_("Longest without intervention"), fmt.metres(f.longest_without_intervention)),
            (_("Interventions"), str(f.interventions)),
            ("MDBI", fmt.estimate(f.mdbi, fmt.metres)),
            (
                _("MDBI %(confidence)s bounds") % {"confidence": conf},
                fmt.bounds(f.mdbi, fmt.metres),
            ),
            ("MTBI", fmt.estimate(f.mtbi, fmt.duration)),
            (
                _("MTBI %(confidence)s bounds") % {"confidence": conf},
                fmt.bounds(f.mtbi, fmt.duration),
            ),
            (_("Interventions per km"), fmt.rate(f.interventions_per_km)),
            (_("Interventions per hour"), fmt.rate(f.interventions_per_hour)),
        ]
    )


def reliability_row(label, f: Figures) -> list:
    return [
        label,
        str(f.interventions),
        fmt.estimate(f.mdbi, fmt.metres),
        fmt.bounds(f.mdbi, fmt.metres),
        fmt.estimate(f.mtbi, fmt.duration),
        fmt.bounds(f.mtbi, fmt.duration),
        fmt.rate(f.interventions_per_km),
        fmt.rate(f.interventions_per_hour),
    ]


def distance_cells(f: Figures) -> list:
    return [
        fmt.metres(f.total_distance),
        fmt.metres(f.auto_distance),
        fmt.percent(f.autonomy_ratio_distance),
        fmt.percent(f.autonomy_ratio_time),
        fmt.metres(f.mean_auto_run),
        fmt.metres(f.max_auto_run),
    ]


def mode_rows(f: Figures) -> list:
    """One row per mode: runs, interventions, time, distance and speed."""
    rows = []
    for label, count, seconds, distance, extra in (
        ("AUTO", f.auto_runs, f.auto_seconds, f.auto_distance, fmt.DASH),
        ("ITO", f.ito_runs, f.manual_seconds, f.manual_distance, str(f.interventions)),
    ):
        kmh = (
            fmt.DASH if seconds <= 0 else fmt.speed(distance * 3.6, seconds).replace("m/s", "km/h")
        )
        rows.append(
            [
                label,
                str(count),
                extra,
                fmt.duration(seconds),
                fmt.metres(distance),
                fmt.speed(distance, seconds),
                kmh,
            ]
        )
    return rows


def test_plan_rows(plan) -> dict | None:
    """The report's "Test plan" section: one row per verdict, the case's own first."""
    if not plan.cases:
        return None
    rows = []
    for case in plan.cases:
        title = f"{case.case.key}: {case.case.title}"
        rows.append([title, f"{case.progress} · {_verdict(case.verdict)}", "", "", ""])
        scoped = [(_("whole case"), v) for v in case.verdicts]
        for leg in case.legs:
            scoped += [(leg.as_dict()["label"], v) for v in leg.verdicts]
        for scope, v in scoped:
            rows.append(["", scope, str(v.criterion), _measured(v), _verdict(v.verdict)])
    unplanned = [f"{leg.shift} · {leg}" for leg in plan.unplanned_legs]
    return {"rows": rows, "unplanned": ", ".join(unplanned) or fmt.DASH}


def _verdict(verdict: str) -> str:
    """A verdict (an API value) as the report's reader says it."""
    return {PASS: _("pass"), FAIL: _("fail"), NOT_YET: _("not yet"), JUDGE: _("needs a judgement")}[
        verdict
    ]


def _measured(v) -> str:
    kind, value = v.criterion.kind, v.measured
    if value is None:
        return v.note or fmt.DASH
    if isinstance(value, list):
        return ", ".join(value) or _("none")
    if kind == "distance_without_intervention":
        return fmt.metres(value)
    if kind == "auto_time_share":
        return fmt.percent(value / 100)
    if kind == "runs_completed":
        return f"{value:.0f}"
    return fmt.decimal(value)
