"""A chart's y axis label stays on the page however wide its tick labels are."""

import numpy as np
import pytest
from PIL import Image

from reports.charts import bars
from reports.selectors.statistics import poisson_estimate

DPI = 100


def ink_columns(path) -> np.ndarray:
    """Per pixel column of the left inch: whether anything is drawn in it."""
    image = Image.open(path).convert("RGBA")
    page = Image.new("RGBA", image.size, "white")
    pixels = np.asarray(Image.alpha_composite(page, image).convert("L"))[:, :DPI]
    return (pixels < 200).any(axis=0)


@pytest.mark.parametrize("exposure", [3_000.0, 9_000_000.0])
def test_the_y_label_is_whole_beside_short_and_long_tick_labels(tmp_path, exposure):
    path = tmp_path / "mtbi.png"
    estimates = [poisson_estimate(exposure, 2), poisson_estimate(exposure * 3, 0)]
    bars.estimate_chart(["Shift 1", "Shift 2"], estimates, str(path), "MTBI", "s", dpi=DPI)
    ink = ink_columns(path)
    # Nothing is cut at the page's edge, and the label is drawn near it.
    assert not ink[:3].any(), np.flatnonzero(ink)[:10]
    assert ink[3 : DPI // 2].any()


def test_long_distances_keep_the_label_whole(tmp_path):
    path = tmp_path / "distance.png"
    bars.distance_chart(["Shift 1"], [4_500_000.0], [120_000.0], str(path), dpi=DPI)
    ink = ink_columns(path)
    assert not ink[:3].any(), np.flatnonzero(ink)[:10]
    assert ink[3 : DPI // 2].any()
