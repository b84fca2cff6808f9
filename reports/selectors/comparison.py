"""Reliability across test events: side-by-side figures, growth and hotspots.

Every figure comes from ``statistics.figures`` over the chosen events' runs,
grouped per test event, per software version and per vehicle, so a
comparison never disagrees with the single-event report.
"""

from collections import defaultdict

from events.models import TestEvent, Vehicle
from reports.selectors.growth import GROWTH_FORMULAS, crow_amsaa
from reports.selectors.hotspots import HOTSPOT_FORMULA, HOTSPOT_RADIUS_M, hotspots
from reports.selectors.statistics import CONFIDENCE, FORMULAS, Run, event_runs, figures
from telemetry.selectors.tracks import GPS


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


def compare(events: list[TestEvent], mode: str = GPS) -> dict:
    """JSON-ready comparison of the given test events, oldest first."""
    events = sorted(events, key=lambda e: (e.start, e.pk))
    runs_of = {e.pk: event_runs(e, mode) for e in events}
    every = [run for e in events for run in runs_of[e.pk]]
    by_version: dict[str, list[Run]] = defaultdict(list)
    by_vehicle: dict[int, list[Run]] = defaultdict(list)
    for e in events:
        for run in runs_of[e.pk]:
            by_version[e.version or "unknown"].append(run)
            by_vehicle[run.vehicle_id].append(run)
    vehicles = {v.pk: v.short_description for v in Vehicle.objects.filter(pk__in=by_vehicle)}
    at, total = growth_points(every)
    fit = crow_amsaa(at, total)
    cumulative = [{"distance": d, "interventions": i + 1} for i, d in enumerate(at)]
    return {
        "mode": mode,
        "confidence": CONFIDENCE,
        "test_events": [
            {
                "id": e.pk,
                "name": str(e),
                "version": e.version,
                "figures": figures(runs_of[e.pk]).as_dict(),
            }
            for e in events
        ],
        "versions": [
            {"version": version, "figures": figures(runs).as_dict()}
            for version, runs in by_version.items()
        ],
        "vehicles": [
            {"id": pk, "name": vehicles.get(pk, str(pk)), "figures": figures(runs).as_dict()}
            for pk, runs in by_vehicle.items()
        ],
        "growth": {
            "points": cumulative,
            "total_distance": total,
            "fit": fit.as_dict() if fit else None,
        },
        "hotspot_radius": HOTSPOT_RADIUS_M,
        "hotspots": hotspots(runs_of, mode),
        "formulas": dict(FORMULAS + GROWTH_FORMULAS + (HOTSPOT_FORMULA,)),
    }
