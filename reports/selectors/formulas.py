"""The definitions behind every reliability figure, as the report's methods
appendix, the comparison and the API print them.

``keyed`` serves the API: the English name is a stable key, the definition is
in the active language. ``shown`` gives both in the active language, for
documents a person reads.
"""

from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

# The radius of one take-over hotspot (reports.selectors.hotspots).
HOTSPOT_RADIUS_M = 25.0

FORMULAS = (
    (
        gettext_noop("Distance"),
        gettext_noop(
            "Sum of geodesic (GPS: WGS84 ellipsoid) or straight (local: map frame) steps along "
            "[segment start] + positions in time order (robot clock, then arrival) + "
            "[start of the next master segment of the same leg]. Positions without a fix are "
            "left out."
        ),
    ),
    (
        gettext_noop("Duration"),
        gettext_noop(
            "end - start of each master segment; an open segment lasts until its newest "
            "position or reason, and every figure including it is provisional."
        ),
    ),
    (
        gettext_noop("Exposure"),
        gettext_noop(
            "D_a, T_a: autonomous distance and time; D_m, T_m: manual (ITO) distance and "
            "time; I: number of interventions."
        ),
    ),
    (
        gettext_noop("Intervention"),
        gettext_noop(
            "An ITO master segment with at least one reason that counts as an intervention; "
            "one with several counted reasons counts once overall and once per reason."
        ),
    ),
    (
        gettext_noop("Unknown mode"),
        gettext_noop(
            "D_u, T_u: distance and time of the segments logged before the robot said its "
            "mode; in the totals, not in autonomy or intervention figures."
        ),
    ),
    (gettext_noop("Autonomy by distance"), "D_a / (D_a + D_m)"),
    (gettext_noop("Autonomy by time"), "T_a / (T_a + T_m)"),
    ("MDBI", gettext_noop("MDBI = D_a / I (mean distance between interventions)")),
    ("MTBI", gettext_noop("MTBI = T_a / I (mean time between interventions)")),
    (
        gettext_noop("Bounds"),
        gettext_noop(
            "Two-sided 90 % bounds for exposure E (homogeneous Poisson process, fixed "
            "exposure): lower = 2E / chi2(0.95; 2I + 2), upper = 2E / chi2(0.05; 2I)."
        ),
    ),
    (
        gettext_noop("No intervention"),
        gettext_noop(
            "I = 0: the estimate is shown as '>= E'; lower bound 2E / chi2(0.95; 2), "
            "no upper bound."
        ),
    ),
    (gettext_noop("Interventions per km"), "I / (D_a / 1000 m)"),
    (gettext_noop("Interventions per hour"), "I / (T_a / 3600 s)"),
    (
        gettext_noop("Mean / longest autonomous run"),
        gettext_noop("Mean and maximum distance of the AUTO segments."),
    ),
    (
        gettext_noop("Longest distance without intervention"),
        gettext_noop(
            "Largest sum of AUTO distance between two interventions of one leg (ITO "
            "segments that are not interventions do not interrupt it)."
        ),
    ),
    (
        gettext_noop("Manual time per reason"),
        gettext_noop(
            "Sum of the durations of the reasons with that key (reasons of one segment "
            "may overlap)."
        ),
    ),
)

GROWTH_FORMULAS = (
    (
        gettext_noop("Crow-AMSAA model"),
        gettext_noop("N(t) = λ t^β, t: cumulative autonomous distance"),
    ),
    (
        gettext_noop("Growth fit"),
        gettext_noop("β = n / Σ ln(T / t_i), λ = n / T^β (time-terminated at T)"),
    ),
    (
        gettext_noop("Growth bounds"),
        gettext_noop(
            "β_L = β χ²(α/2; 2n) / (2n), β_U = β χ²(1 − α/2; 2n) / (2n), α = 1 − confidence"
        ),
    ),
    (gettext_noop("Duane growth parameter"), "1 − β"),
    (
        gettext_noop("Confidence band"),
        gettext_noop("N(t) = n (t / T)^β for β from β_L to β_U"),
    ),
)

HOTSPOT_FORMULA = (
    gettext_noop("Take-over hotspots"),
    gettext_noop(
        "Take-overs (start of an intervention's ITO segment) at most %(radius)s m apart "
        "are one hotspot, and so is every take-over linked to it through such pairs "
        "(single linkage). Hotspots are numbered by size, then by their first take-over."
    ),
)


def _definition(text: str) -> str:
    return _(text) % {"radius": f"{HOTSPOT_RADIUS_M:g}"} if "%(" in text else _(text)


def keyed(pairs) -> dict[str, str]:
    """Each definition in the active language under its English name, in order."""
    return {name: _definition(text) for name, text in pairs}


def translated_definitions(pairs) -> dict[str, str]:
    """Each name and definition in the active language, in order."""
    return {_(name): _definition(text) for name, text in pairs}
