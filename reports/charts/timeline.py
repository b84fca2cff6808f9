"""The mode timeline of a shift: AUTO, ITO and unknown-mode runs, reasons, weather, goals."""

from collections import defaultdict
from datetime import timedelta

import matplotlib
from django.utils.translation import gettext as _

matplotlib.use("Agg")

import matplotlib.dates as mdates  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from django.utils.translation import gettext  # noqa: E402

from reports import formatting as fmt  # noqa: E402
from reports.charts import style, weather  # noqa: E402
from reports.charts.style import rgb  # noqa: E402

MARKER_REASONS = ("goal", "end_shift")
WEATHER_ROW = -1.2  # a band above the AUTO bars
MODE_COLORS = {"auto": "#2ca02c", "ito": "#d62728", "unknown": "#969696"}


def time_axis(first, last, min_span=timedelta(0)):
    """The drawn time range: the runs with a small margin, at least ``min_span`` long."""
    span = max(last - first, timedelta(seconds=60), min_span)
    return first - span * 0.02, first + span * 1.02


class DistinctTimeLocator(mdates.AutoDateLocator):
    """Round local times, each instant once: on the day the clocks go forward the
    skipped hour's tick (02:00) falls on the next one (03:00) and would repeat it."""

    def __call__(self):
        return np.unique(super().__call__())

    def tick_values(self, vmin, vmax):
        return np.unique(super().tick_values(vmin, vmax))


def set_time_ticks(ax, tz, span: timedelta) -> None:
    """Ticks at round times, each labelled as finely as their step needs, with the
    day when the axis spans more than one: no label is written twice."""
    locator = DistinctTimeLocator(tz=tz, minticks=3, maxticks=9)
    day = fmt.day_of_month_pattern()
    clock = f"{day} %H:%M" if span > timedelta(days=1) else "%H:%M"
    formatter = mdates.AutoDateFormatter(locator, tz=tz)
    # Keyed by the locator's tick unit in days (year, month, day, hour, minute, second).
    formatter.scaled = {
        365.0: "%Y",
        30.0: "%m.%Y",
        1.0: day,
        1 / 24: clock,
        1 / (24 * 60): clock,
        1 / (24 * 3600): "%H:%M:%S",
    }
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(formatter)


def draw_timeline(
    shift_runs, reasons, weather_changes, tz, path, dpi=150, min_span=timedelta(0)
) -> str:
    """``shift_runs``: runs of one shift; ``reasons``: ItoReason by key;
    ``weather_changes``: [(time, label, icon key)], drawn as a symbol and its
    name above the bars.  Times are drawn in ``tz``."""
    reason_rows = sorted(
        {span.reason for run in shift_runs for span in run.reasons},
        key=lambda key: reasons[key].shown_short if key in reasons else key,
    )
    # The unknown mode has a row only in a shift that has such a run.
    modes = ["auto", "ito"] + (["unknown"] if any(r.kind == "unknown" for r in shift_runs) else [])
    mode_labels = {"auto": "AUTO", "ito": "ITO", "unknown": _("Unknown mode")}
    labels = [mode_labels[m] for m in modes] + [
        reasons[key].shown_short if key in reasons else key for key in reason_rows
    ]
    height = 1.2 + 0.28 * len(labels) + (0.3 if weather_changes else 0.0)
    fig, ax = style.fixed_chart(7.0, height, style.label_width(labels) + 0.2, top=0.08)
    row_of = {key: len(modes) + i for i, key in enumerate(reason_rows)}
    ax.xaxis_date(tz)
    # Bars of one row, colour and hatch are one collection, markers of one colour one
    # scatter: a shift has hundreds of runs, too many for an artist each.
    bars: dict[tuple, list] = defaultdict(list)
    markers: dict[tuple, list] = defaultdict(list)
    for run in shift_runs:
        row, color = modes.index(run.kind), MODE_COLORS[run.kind]
        bars[(row, color, 0.6, "//" if run.is_open else None)].append((run.start, run.end))
        for span in run.reasons:
            catalogue = reasons.get(span.reason)
            color = rgb(catalogue.color) if catalogue else (0.5, 0.5, 0.5)
            if span.end == span.start or span.reason in MARKER_REASONS:
                markers[color].append((span.start, row_of[span.reason]))
            else:
                bars[(row_of[span.reason], color, 0.5, None)].append((span.start, span.end))
    for (row, color, height, hatch), spans in bars.items():
        starts = mdates.date2num([start for start, _ in spans])
        ends = mdates.date2num([end for _, end in spans])
        ax.broken_barh(
            list(zip(starts, ends - starts, strict=True)),
            (row - height / 2, height),
            facecolors=color,
            edgecolor="black",
            linewidth=0.3,
            hatch=hatch,
        )
    for color, points in markers.items():
        ax.scatter(
            mdates.date2num([when for when, _ in points]),
            [row for _, row in points],
            color=color,
            edgecolors="black",
            zorder=3,
        )
    first = min(run.start for run in shift_runs)
    last = max(run.end for run in shift_runs)
    start, end = time_axis(first, last, min_span)
    ax.set_xlim(start, end)
    for when, label, icon in weather_changes:
        # A leg opened long before its first segment would squeeze the runs.
        when = min(max(when, first), last)
        ax.axvline(when, color="#1f77b4", linewidth=0.6, linestyle="--")
        weather.place(ax, when, WEATHER_ROW, icon)
        ax.annotate(
            label,
            (when, WEATHER_ROW),
            xytext=(weather.SIZE + 2, 0),
            textcoords="offset points",
            fontsize=6,
            color="#1f77b4",
            va="center",
        )
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    ax.set_ylim(len(labels) - 0.5, WEATHER_ROW - 0.55 if weather_changes else -0.9)
    set_time_ticks(ax, tz, end - start)
    ax.tick_params(axis="x", labelsize=7)
    ax.set_xlabel(gettext("time (%(zone)s)") % {"zone": tz.key}, fontsize=7)
    ax.grid(True, axis="x", linewidth=0.3, alpha=0.6)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
