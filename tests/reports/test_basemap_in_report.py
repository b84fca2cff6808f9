"""A report of an event with an orthophoto basemap shows the orthophoto under its tracks."""

import numpy as np
from PIL import Image

from basemaps.services import layers
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from telemetry.models import Pose
from tests.support.basemaps import QUADRANTS, quadrant_geotiff
from tests.support.pdf import flat, pdf_text, save_pages


def pixels_near(pages, colour, tolerance=14) -> int:
    total = 0
    for page in pages:
        rgb = np.asarray(Image.open(page).convert("RGB")).astype(int)
        total += int((np.abs(rgb - colour).max(axis=2) <= tolerance).sum())
    return total


def test_the_report_draws_the_events_orthophoto_without_any_tile_server(
    scenario, settings, tmp_path
):
    settings.FTT_TILE_URL = "http://127.0.0.1:9/{z}/{x}/{y}.png"  # nothing listens there
    lons, lats = zip(*(p.point.coords for p in Pose.objects.all()), strict=True)
    centre = ((min(lons) + max(lons)) / 2, (min(lats) + max(lats)) / 2)
    span_m = max(max(lons) - min(lons), max(lats) - min(lats)) * 111_000
    tif = quadrant_geotiff(tmp_path / "ortho.tif", pixel_m=3 * span_m / 512, centre=centre)
    layer = layers.register_file(tif, name="Ortho", attribution="Drone 2026")
    layers.set_event_default(scenario.event, layer)

    result = render_report(scenario.event, ReportOptions())

    assert result.tiles_used
    text = flat(pdf_text(result.pdf, tmp_path, layout=False))
    assert "Map: basemap “Ortho” (Drone 2026), drawn by FTT" in text
    pages = save_pages(result.pdf, "basemap-orthophoto", dpi=50)
    for name, colour in QUADRANTS.items():
        assert pixels_near(pages, colour) > 500, name
