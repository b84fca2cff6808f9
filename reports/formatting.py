"""How figures are written in the report, CSV and GUI: one place, one precision."""

import math
from datetime import datetime, tzinfo

from reports.selectors.statistics import Estimate

DASH = "–"


def metres(value: float | None) -> str:
    return DASH if value is None else f"{value:.2f} m"


def duration(seconds: float | None) -> str:
    """H:MM:SS, rounded to the second."""
    if seconds is None or math.isnan(seconds):
        return DASH
    total = int(round(seconds))
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}"


def percent(ratio: float | None) -> str:
    return DASH if ratio is None else f"{100 * ratio:.1f} %"


def rate(value: float | None) -> str:
    return DASH if value is None else f"{value:.3f}"


def speed(distance: float, seconds: float) -> str:
    return DASH if seconds <= 0 else f"{distance / seconds:.2f} m/s"


def timestamp(value: datetime | None, tz: tzinfo) -> str:
    return DASH if value is None else value.astimezone(tz).strftime("%Y-%m-%d %H:%M:%S")


def clock(value: datetime | None, tz: tzinfo) -> str:
    return DASH if value is None else value.astimezone(tz).strftime("%H:%M:%S")


def estimate(value: Estimate, unit) -> str:
    """The point estimate, or '≥ exposure' when there was no intervention."""
    if value.censored:
        return f"≥ {unit(value.exposure)}"
    return unit(value.value)


def bounds(value: Estimate, unit) -> str:
    if value.lower is None:
        return DASH
    upper = "∞" if value.upper is None else unit(value.upper)
    return f"{unit(value.lower)} – {upper}"
