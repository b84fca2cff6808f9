"""A chart's legend covers no bar and no bar's figure."""

import pytest

from events.models import ItoReason
from reports.charts import bars


@pytest.fixture
def drawn(monkeypatch):
    """The figures the charts draw, kept open after they are saved."""
    figures = []
    monkeypatch.setattr(bars.plt, "close", figures.append)
    return figures


def covered(fig) -> list:
    """The bars and texts of the chart's axes that its legend's box overlaps."""
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    return [
        artist
        for artist in [*ax.patches, *ax.texts]
        if artist.get_window_extent(renderer).overlaps(legend)
    ]


def test_the_distance_legend_leaves_bars_and_their_figures_readable(tmp_path, drawn):
    bars.distance_chart(
        ["Shift 1", "Shift 2", "Shift 3"], [900.0] * 3, [400.0] * 3, str(tmp_path / "d.png")
    )
    assert covered(drawn[0]) == []


def test_the_reasons_legend_covers_no_bar(tmp_path, drawn):
    # Every bar as tall as the axes: no corner inside them is free.
    reasons = {
        key: ItoReason(key=key, short_description=f"reason {key}", color="10,120,200")
        for key in "abcdef"
    }
    counts = [{key: 6 for key in reasons}, {key: 6 for key in reasons}]
    bars.reasons_chart(["Shift 1", "Shift 2"], counts, reasons, str(tmp_path / "r.png"))
    assert covered(drawn[0]) == []
