"""Figures in the active language (django.utils.formats), for what commands print
and the collector says; the PDF report has its own, reports.formatting."""

import math

from django.utils.formats import number_format


def short(value: float) -> str:
    """As short as it reads: 30, 2.5 (German 2,5)."""
    if math.isfinite(value) and value == int(value):
        return number_format(int(value))
    return number_format(value)
