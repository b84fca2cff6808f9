"""How figures are written in the report, CSV and GUI: one place, one precision."""

import math
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from datetime import date, datetime, tzinfo

from django.utils import numberformat, translation
from django.utils.formats import get_format

from reports.selectors.statistics import Estimate

DASH = "–"

# The language figures are written in. Only the PDF report sets it (written_in):
# CSV and the API keep the decimal point whatever the reader's language.
_LANGUAGE: ContextVar[str] = ContextVar("ftt_report_language", default="en")
# Per language: the decimal mark and how a date and time are written.
_DECIMAL = {"de": ","}
_TIMESTAMP = {"de": "%d.%m.%Y %H:%M:%S"}
_DAY = {"de": "%d.%m.%Y"}
_DAY_OF_MONTH = {"de": "%d.%m."}
# The languages whose figures group thousands (German 1.227,47; English 1227.47).
_GROUPED = {"de"}


@contextmanager
def written_in(language: str) -> Iterator[None]:
    """Words (gettext) and figures in ``language`` until the block ends."""
    token = _LANGUAGE.set(language)
    try:
        with translation.override(language):
            yield
    finally:
        _LANGUAGE.reset(token)


def localised(text: str) -> str:
    """Text with figures written with a decimal point, in the report's language
    (also what the figures' tick labels go through, reports.charts.style)."""
    mark = _DECIMAL.get(_LANGUAGE.get())
    return text.replace(".", mark) if mark else text


def _grouped(figure: str) -> str:
    """A figure written with a decimal point ("1227.47", rounded already) with the
    report language's decimal mark and, where it groups them, thousands
    separator."""
    language = _LANGUAGE.get()
    return numberformat.format(
        figure,
        get_format("DECIMAL_SEPARATOR", language),
        None,
        get_format("NUMBER_GROUPING", language),
        get_format("THOUSAND_SEPARATOR", language),
        force_grouping=language in _GROUPED,
    )


def decimal(value: float, places: int = 2) -> str:
    return _grouped(f"{value:.{places}f}")


def number(value: float) -> str:
    """A plain figure, as short as it reads (25, 2.5)."""
    short = f"{value:g}"
    return localised(short) if "e" in short else _grouped(short)


def metres(value: float | None) -> str:
    return DASH if value is None else _grouped(f"{value:.2f}") + " m"


def duration(seconds: float | None) -> str:
    """H:MM:SS, rounded to the second."""
    if seconds is None or math.isnan(seconds):
        return DASH
    total = int(round(seconds))
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}"


def percent(ratio: float | None) -> str:
    return DASH if ratio is None else localised(f"{100 * ratio:.1f}") + " %"


def rate(value: float | None) -> str:
    return DASH if value is None else localised(f"{value:.3f}")


def speed(distance: float, seconds: float) -> str:
    return DASH if seconds <= 0 else localised(f"{distance / seconds:.2f}") + " m/s"


def timestamp(value: datetime | None, tz: tzinfo) -> str:
    pattern = _TIMESTAMP.get(_LANGUAGE.get(), "%Y-%m-%d %H:%M:%S")
    return DASH if value is None else value.astimezone(tz).strftime(pattern)


def day(value: date) -> str:
    return value.strftime(_DAY.get(_LANGUAGE.get(), "%Y-%m-%d"))


def day_of_month_pattern() -> str:
    """The strftime pattern of a day without its year, for a time axis."""
    return _DAY_OF_MONTH.get(_LANGUAGE.get(), "%m-%d")


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
