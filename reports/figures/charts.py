"""Bar charts of the global statistics, one group per shift."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from reports.figures.style import rgb  # noqa: E402


def distance_chart(labels, auto, manual, path, dpi=150) -> str:
    """Stacked autonomous and manual distance per shift, with the autonomy share."""
    fig, ax = plt.subplots(figsize=(7.0, 3.0), layout="constrained")
    x = np.arange(len(labels))
    ax.bar(x, auto, color="#2ca02c", label="AUTO")
    ax.bar(x, manual, bottom=auto, color="#d62728", label="ITO (manual)")
    for i, (a, m) in enumerate(zip(auto, manual, strict=True)):
        share = f"{100 * a / (a + m):.1f} % auto" if a + m > 0 else "no distance"
        ax.text(i, a + m, f"{a + m:.0f} m\n{share}", ha="center", va="bottom", fontsize=6)
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_ylabel("distance [m]", fontsize=7)
    ax.margins(y=0.25)
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def reasons_chart(labels, counts_by_shift, reasons, path, dpi=150) -> str:
    """Interventions per reason per shift; ``counts_by_shift``: [{key: n}]."""
    keys = sorted({k for counts in counts_by_shift for k in counts})
    fig, ax = plt.subplots(figsize=(7.0, 3.0), layout="constrained")
    x = np.arange(len(labels))
    width = 0.8 / max(len(keys), 1)
    for i, key in enumerate(keys):
        catalogue = reasons.get(key)
        values = [counts.get(key, 0) for counts in counts_by_shift]
        ax.bar(
            x - 0.4 + width * (i + 0.5),
            values,
            width,
            color=rgb(catalogue.color) if catalogue else "grey",
            label=catalogue.short_description if catalogue else key,
        )
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_ylabel("interventions", fontsize=7)
    ax.yaxis.get_major_locator().set_params(integer=True)
    if keys:
        ax.legend(fontsize=6, ncols=min(len(keys), 4))
    else:
        ax.text(0.5, 0.5, "no interventions", transform=ax.transAxes, ha="center")
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def mdbi_chart(labels, estimates, path, dpi=150) -> str:
    """MDBI per shift with its 90 % bounds; censored shifts show their lower bound."""
    fig, ax = plt.subplots(figsize=(7.0, 2.6), layout="constrained")
    for i, est in enumerate(estimates):
        if est.lower is None:
            continue
        top = est.upper if est.upper is not None else est.exposure * 3
        ax.plot([i, i], [est.lower, top], color="black", linewidth=1)
        if est.value is not None:
            ax.plot(i, est.value, "o", color="#1f77b4")
        else:
            ax.plot(i, est.exposure, "^", color="#1f77b4")
    ax.set_xticks(range(len(labels)), labels, fontsize=7)
    ax.set_xlim(-0.5, len(labels) - 0.5)
    ax.set_ylabel("MDBI [m]", fontsize=7)
    ax.set_yscale("log")
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
