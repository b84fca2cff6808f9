"""Bar charts of the global statistics, one group per shift.

Charts are SVG with their text kept as text: typst sets it in the report's
fonts, so titles and axis labels are sharp and searchable in the PDF.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from django.utils.translation import gettext as _  # noqa: E402

from reports import formatting as fmt  # noqa: E402
from reports.charts.style import fit_y_ticks, fixed_chart, label_width, rgb  # noqa: E402

# Inches left of the axes for the y label and short tick labels; longer ones
# widen it (fit_y_ticks).
CHART_LEFT = 0.75
# Legend rows beside the axes before a second column starts.
LEGEND_ROWS = 14


def legend_width(labels, size: float, columns: int = 1) -> float:
    """Inches right of the axes for a legend of ``labels``: handle, gap and text
    per column."""
    return columns * (label_width(labels, size) + 0.45) + 0.1


def place_legend(ax, size: float, columns: int = 1) -> None:
    """The legend beside the axes, where it covers no bar and no bar's number."""
    ax.legend(
        fontsize=size, ncols=columns, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0
    )


def distance_chart(labels, auto, manual, path, dpi=150) -> str:
    """Stacked autonomous and manual distance per shift, with the autonomy share."""
    names = ["AUTO", _("ITO (manual)")]
    fig, ax = fixed_chart(7.0, 3.0, CHART_LEFT, right=legend_width(names, 7))
    x = np.arange(len(labels))
    ax.bar(x, auto, color="#2ca02c", label=names[0])
    ax.bar(x, manual, bottom=auto, color="#d62728", label=names[1])
    for i, (a, m) in enumerate(zip(auto, manual, strict=True)):
        share = (
            _("%(share)s auto") % {"share": fmt.percent(a / (a + m))}
            if a + m > 0
            else _("no distance")
        )
        ax.text(i, a + m, f"{a + m:.0f} m\n{share}", ha="center", va="bottom", fontsize=6)
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_title(_("Distance per shift: autonomous and manual"))
    ax.set_ylabel(_("distance [m]"), fontsize=7)
    ax.margins(y=0.25)
    place_legend(ax, 7)
    fit_y_ticks(fig, ax)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def reasons_chart(labels, counts_by_shift, reasons, path, dpi=150) -> str:
    """Interventions per reason per shift; ``counts_by_shift``: [{key: n}]."""
    keys = sorted({k for counts in counts_by_shift for k in counts})
    names = [reasons[key].shown_short if key in reasons else key for key in keys]
    columns = -(-len(keys) // LEGEND_ROWS)
    right = legend_width(names, 6, columns) if keys else 0.15
    fig, ax = fixed_chart(7.0, 3.0, CHART_LEFT, right=right)
    x = np.arange(len(labels))
    width = 0.8 / max(len(keys), 1)
    for i, (key, name) in enumerate(zip(keys, names, strict=True)):
        catalogue = reasons.get(key)
        values = [counts.get(key, 0) for counts in counts_by_shift]
        ax.bar(
            x - 0.4 + width * (i + 0.5),
            values,
            width,
            color=rgb(catalogue.color) if catalogue else "grey",
            label=name,
        )
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_title(_("Interventions per shift by reason"))
    ax.set_ylabel(_("interventions [count]"), fontsize=7)
    ax.yaxis.get_major_locator().set_params(integer=True)
    if keys:
        place_legend(ax, 6, columns)
    else:
        ax.text(0.5, 0.5, _("no interventions"), transform=ax.transAxes, ha="center")
    fit_y_ticks(fig, ax)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def estimate_chart(labels, estimates, path, name, unit, scale=1.0, dpi=150) -> str:
    """MDBI or MTBI per shift with its 90 % bounds as error bars, on a linear
    axis; values are divided by ``scale`` (e.g. 3600 for hours).

    A shift without interventions has no estimate: its lower bound is drawn
    as an upward arrow from the bound ("at least").
    """
    fig, ax = fixed_chart(7.0, 2.8, CHART_LEFT)
    for i, est in enumerate(estimates):
        if est.value is not None:
            value, lower, upper = est.value / scale, est.lower / scale, est.upper / scale
            ax.errorbar(
                i,
                value,
                yerr=[[value - lower], [upper - value]],
                fmt="o",
                color="#1f77b4",
                capsize=4,
            )
        elif est.lower is not None:
            lower = est.lower / scale
            ax.plot(i, lower, "_", color="#1f77b4", markersize=12)
            ax.annotate(
                "",
                xy=(i, lower * 1.6),
                xytext=(i, lower),
                arrowprops={"arrowstyle": "->", "color": "#1f77b4"},
            )
    ax.set_xticks(range(len(labels)), labels, fontsize=7)
    ax.set_xlim(-0.5, len(labels) - 0.5)
    ax.set_ylim(bottom=0)
    ax.set_title(
        _("%(name)s per shift with 90 %% bounds (arrow: no intervention, lower bound)")
        % {"name": name}
    )
    ax.set_ylabel(f"{name} [{unit}]", fontsize=7)
    ax.ticklabel_format(axis="y", style="plain", useOffset=False)
    fit_y_ticks(fig, ax)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
