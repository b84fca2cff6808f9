"""Charts of the comparison report: reliability growth and take-over hotspots."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from django.utils.translation import gettext as _  # noqa: E402

from reports import formatting as fmt  # noqa: E402
from reports.charts.style import fixed_chart, new_chart, rgb  # noqa: E402


def growth_chart(points, total, fit, path) -> str:
    """Cumulative interventions against cumulative autonomous distance (km),
    with the Crow-AMSAA fit and its band when there is one."""
    fig, ax = new_chart((7.0, 3.2), layout="constrained")
    km = [p["distance"] / 1000 for p in points]
    ax.step(
        km, [p["interventions"] for p in points], where="post", color="black", label=_("observed")
    )
    ax.plot(km, [p["interventions"] for p in points], "o", color="black", markersize=3)
    if fit is not None:
        t = np.linspace(total / 200, total, 200)
        n, beta = fit["interventions"], fit["beta"]
        ax.plot(
            t / 1000,
            n * (t / total) ** beta,
            color="#1f77b4",
            label=f"Crow-AMSAA, β = {fmt.decimal(beta)}",
        )
        ax.fill_between(
            t / 1000,
            n * (t / total) ** fit["beta_upper"],
            n * (t / total) ** fit["beta_lower"],
            color="#1f77b4",
            alpha=0.2,
            label=_("90 % band"),
        )
    ax.set_title(_("Reliability growth: cumulative interventions"))
    ax.set_xlabel(_("cumulative autonomous distance [km]"), fontsize=7)
    ax.set_ylabel(_("interventions [count]"), fontsize=7)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    fig.savefig(path)
    plt.close(fig)
    return path


def hotspot_chart(spots, reasons, path) -> str | None:
    """Take-over start positions in metres around their centre, each coloured
    by its (first) reason; every hotspot is circled and carries its number,
    the number of the table below the map."""
    members = [m for spot in spots for m in spot["members"]]
    if not members:
        return None
    fig, ax = fixed_chart(7.0, 4.5, 0.75)
    keys = [m["reasons"][0] if m["reasons"] else "unassigned" for m in members]
    east = np.array([m["east"] for m in members])
    north = np.array([m["north"] for m in members])
    for key in sorted(set(keys)):
        chosen = [i for i, k in enumerate(keys) if k == key]
        reason = reasons.get(key)
        ax.scatter(
            east[chosen],
            north[chosen],
            s=25,
            color=rgb(reason.color) if reason else "grey",
            edgecolors="black",
            linewidths=0.4,
            label=reason.shown_short if reason else _("unassigned"),
            zorder=3,
        )
    for spot in spots:
        ax.annotate(
            str(spot["number"]),
            (spot["east"], spot["north"]),
            xytext=(6, 6),
            textcoords="offset points",
            fontsize=8,
            fontweight="bold",
            bbox={"boxstyle": "circle,pad=0.2", "facecolor": "white", "edgecolor": "black"},
            zorder=4,
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.15)
    ax.set_title(_("Take-over hotspots: where interventions started (numbers: table below)"))
    ax.set_xlabel(_("east [m]"), fontsize=7)
    ax.set_ylabel(_("north [m]"), fontsize=7)
    ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.legend(fontsize=7)
    fig.savefig(path)
    plt.close(fig)
    return path
