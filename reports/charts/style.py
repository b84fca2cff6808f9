"""Colours and fonts shared by every chart of a report."""

import logging

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import font_manager  # noqa: E402
from matplotlib.ticker import ScalarFormatter  # noqa: E402

from reports import formatting as fmt  # noqa: E402

# Latin/Greek/Cyrillic first, then CJK fonts; matplotlib falls back glyph by
# glyph along this list, so a reason or name in any of them renders.
FONT_FAMILIES = ("DejaVu Sans", "WenQuanYi Micro Hei", "Noto Sans CJK JP", "Noto Sans CJK SC")


def rgb(value: str, default=(0.5, 0.5, 0.5)) -> tuple[float, float, float]:
    """Catalogue colour 'R,G,B' (0-255) as a matplotlib colour."""
    try:
        r, g, b = (int(part) for part in value.split(","))
    except (AttributeError, ValueError):
        return default
    return (r / 255, g / 255, b / 255)


def installed_families() -> list[str]:
    names = {f.name for f in font_manager.fontManager.ttflist}
    return [family for family in FONT_FAMILIES if family in names] or ["DejaVu Sans"]


def apply() -> None:
    # The CJK fonts have no bold face; matplotlib says so on every bold label.
    logging.getLogger("matplotlib.font_manager").setLevel(logging.ERROR)
    matplotlib.rcParams["font.family"] = installed_families()
    matplotlib.rcParams["axes.titlesize"] = 9
    # Text stays text in SVG charts (typst sets it), instead of outlines.
    matplotlib.rcParams["svg.fonttype"] = "none"


class LocalNumbers(ScalarFormatter):
    """Tick labels with the decimal mark of the report's language (reports.formatting)."""

    def __call__(self, x, pos=None):
        return fmt.localised(super().__call__(x, pos))

    def get_offset(self):
        return fmt.localised(super().get_offset())


def localise_ticks(ax) -> None:
    """Number both axes in the report's language.  Dates and named ticks set later
    (xaxis_date, set_xticks with labels) replace it on their axis."""
    ax.xaxis.set_major_formatter(LocalNumbers())
    ax.yaxis.set_major_formatter(LocalNumbers())


def new_chart(size, **options):
    """A chart: figure and one axes (plt.subplots), numbered in the report's language:
    every chart of a report is made here or by fixed_chart."""
    fig, ax = plt.subplots(figsize=size, **options)
    localise_ticks(ax)
    return fig, ax


def fixed_chart(
    width: float,
    height: float,
    left: float,
    bottom: float = 0.45,
    top: float = 0.3,
    right: float = 0.15,
):
    """A chart: figure and axes with margins in inches given by the caller.  A constrained
    layout measures every text several times, most of a chart's or timeline's
    drawing time; the caller knows its widest text in advance, except a chart's
    y tick labels, which widen the margin once drawn (fit_y_ticks)."""
    fig = plt.figure(figsize=(width, height))
    ax = fig.add_axes(
        (left / width, bottom / height, 1 - (left + right) / width, 1 - (bottom + top) / height)
    )
    localise_ticks(ax)
    return fig, ax


def label_width(labels, size_pt: float = 7.0) -> float:
    """Inches a column of labels needs: about 0.6 em per character."""
    return max((len(label) for label in labels), default=0) * size_pt * 0.6 / 72


# Inches kept free left of the y axis label.
Y_LABEL_MARGIN = 0.05


def fit_y_ticks(fig, ax) -> None:
    """Widen the axes' left margin where the y axis (tick labels and label)
    needs more than it gives: a fixed margin is chosen before the data's
    numbers are known.  Measures the y axis alone, once."""
    used = ax.yaxis.get_tightbbox(fig.canvas.get_renderer())
    short = (Y_LABEL_MARGIN * fig.dpi - used.x0) / (fig.get_figwidth() * fig.dpi)
    if short > 0:
        box = ax.get_position()
        ax.set_position((box.x0 + short, box.y0, box.width - short, box.height))
