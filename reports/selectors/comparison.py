"""Reliability across test events: side-by-side figures, growth and hotspots.

Every figure comes from ``statistics.figures`` over the chosen events' runs,
grouped per test event, per software version and per vehicle, so a
comparison never disagrees with the single-event report.
"""

from collections import defaultdict

from django.utils.translation import gettext as _

from common import cyclic_gc
from events.models import ItoReason, TestEvent, Vehicle
from reports import formatting as fmt
from reports.selectors import formulas
from reports.selectors.growth import crow_amsaa
from reports.selectors.hotspots import hotspots
from reports.selectors.statistics import CONFIDENCE, Estimate, Run, campaign_runs, figures
from telemetry.storage.keys import GPS_TRACK


def growth_points(runs: list[Run]) -> tuple[list[float], float]:
    """Cumulative autonomous distance at each intervention, and the total.

    Runs are taken in driving order; an intervention happens at the distance
    driven autonomously before it.
    """
    driven = 0.0
    at = []
    for run in runs:
        if run.kind == "auto":
            driven += run.distance
        elif run.is_intervention:
            at.append(driven)
    return at, driven


def written_figures(f: dict) -> dict[str, str]:
    """A group's figures as the PDF writes them (reports.formatting), so the GUI
    shows the same text without deciding any rounding or unit itself."""
    mdbi, mtbi = Estimate(**f["mdbi"]), Estimate(**f["mtbi"])
    return {
        "interventions": str(f["interventions"]),
        "auto_distance": fmt.metres(f["auto_distance"]),
        "auto_time": fmt.duration(f["auto_seconds"]),
        "mdbi": fmt.estimate(mdbi, fmt.metres),
        "mdbi_bounds": fmt.bounds(mdbi, fmt.metres),
        "mtbi": fmt.estimate(mtbi, fmt.duration),
        "mtbi_bounds": fmt.bounds(mtbi, fmt.duration),
        "per_km": fmt.rate(f["interventions_per_km"]),
        "per_hour": fmt.rate(f["interventions_per_hour"]),
    }


def fit_rows(fit: dict | None) -> list[list[str]]:
    """The growth fit as label/value rows (PDF and GUI); empty without a fit."""
    if fit is None:
        return []
    return [
        [_("Interventions n"), str(fit["interventions"])],
        [_("Autonomous distance T"), fmt.metres(fit["exposure"])],
        ["β", _with_bounds(fit["beta"], fit["beta_lower"], fit["beta_upper"])],
        [
            _("Growth parameter 1 − β"),
            _with_bounds(fit["growth"], fit["growth_lower"], fit["growth_upper"]),
        ],
    ]


def _with_bounds(value: float, lower: float, upper: float) -> str:
    return f"{fmt.rate(value)} (90 %: {fmt.rate(lower)} – {fmt.rate(upper)})"


def _group(extra: dict, runs: list[Run]) -> dict:
    data = figures(runs).as_dict()
    return {**extra, "figures": data, "shown": written_figures(data)}


@cyclic_gc.paused()
def compare(events: list[TestEvent], mode: str = GPS_TRACK) -> dict:
    """JSON-ready comparison of the given test events, oldest first."""
    events = sorted(events, key=lambda e: (e.start, e.pk))
    runs_of = campaign_runs(events, mode)
    every = [run for e in events for run in runs_of[e.pk]]
    by_version: dict[str, list[Run]] = defaultdict(list)
    by_vehicle: dict[int, list[Run]] = defaultdict(list)
    for e in events:
        version = by_version[e.version or _("unknown")]
        for run in runs_of[e.pk]:
            version.append(run)
            by_vehicle[run.vehicle_id].append(run)
    vehicles = {v.pk: v.short_description for v in Vehicle.objects.filter(pk__in=by_vehicle)}
    at, total = growth_points(every)
    fit = crow_amsaa(at, total)
    cumulative = [{"distance": d, "interventions": i + 1} for i, d in enumerate(at)]
    return {
        "mode": mode,
        "confidence": CONFIDENCE,
        "test_events": [
            _group(
                {"id": e.pk, "name": str(e), "version": e.version, "start": e.start.isoformat()},
                runs_of[e.pk],
            )
            for e in events
        ],
        "versions": [_group({"version": version}, runs) for version, runs in by_version.items()],
        "vehicles": [
            _group({"id": pk, "name": vehicles.get(pk, str(pk))}, runs)
            for pk, runs in by_vehicle.items()
        ],
        "growth": {
            "points": cumulative,
            "total_distance": total,
            "fit": fit.as_dict() if fit else None,
            "fit_rows": fit_rows(fit.as_dict() if fit else None),
        },
        "reasons": {
            r.key: {"name": r.short_description, "color": r.color} for r in ItoReason.objects.all()
        },
        "hotspot_radius": formulas.HOTSPOT_RADIUS_M,
        "hotspots": hotspots(runs_of, mode),
        "formulas": formulas.keyed(
            formulas.FORMULAS + formulas.GROWTH_FORMULAS + (formulas.HOTSPOT_FORMULA,)
        ),
    }
