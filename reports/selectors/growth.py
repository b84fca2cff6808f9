"""Reliability growth: the Crow-AMSAA (Duane) model over autonomous distance.

Interventions are taken as a non-homogeneous Poisson process in the
cumulative autonomous distance t, with expected count N(t) = λ t^β.  β < 1
means interventions become rarer as driving goes on; the Duane growth
parameter is 1 − β.  The data end at the total distance T (time-terminated),
so with n interventions at t_1 … t_n (MIL-HDBK-189):

  β̂ = n / Σ ln(T / t_i),   λ̂ = n / T^β̂,
  2nβ / β̂ ~ χ²(2n), so the two-sided bounds are
  β_L = β̂ χ²(α/2; 2n) / (2n),  β_U = β̂ χ²(1 − α/2; 2n) / (2n).

The band drawn around the fitted curve is N(t) = n (t/T)^β for β between its
bounds: the curves through the observed end point with the extreme slopes.
"""

import math
from dataclasses import dataclass

from scipy.stats import chi2

from reports.selectors.statistics import CONFIDENCE


@dataclass
class GrowthFit:
    n: int
    total: float
    beta: float
    lam: float
    beta_lower: float
    beta_upper: float

    @property
    def growth(self) -> float:
        return 1.0 - self.beta

    def expected(self, t: float, beta: float | None = None) -> float:
        """Expected cumulative interventions at t; with ``beta``, the band's curve."""
        if beta is None:
            return self.lam * t**self.beta
        return self.n * (t / self.total) ** beta

    def as_dict(self) -> dict:
        return {
            "interventions": self.n,
            "exposure": self.total,
            "beta": self.beta,
            "lambda": self.lam,
            "beta_lower": self.beta_lower,
            "beta_upper": self.beta_upper,
            "growth": self.growth,
            "growth_lower": 1.0 - self.beta_upper,
            "growth_upper": 1.0 - self.beta_lower,
        }


def crow_amsaa(events: list[float], total: float, confidence: float = CONFIDENCE):
    """Fit of interventions at cumulative distances ``events`` up to ``total``;
    None when there are fewer than two interventions or no distance."""
    points = [t for t in events if t > 0]
    n = len(points)
    if n < 2 or total <= 0 or all(t >= total for t in points):
        return None
    beta = n / sum(math.log(total / t) for t in points)
    alpha = 1.0 - confidence
    return GrowthFit(
        n=n,
        total=total,
        beta=beta,
        lam=n / total**beta,
        beta_lower=beta * chi2.ppf(alpha / 2.0, 2 * n) / (2 * n),
        beta_upper=beta * chi2.ppf(1.0 - alpha / 2.0, 2 * n) / (2 * n),
    )
