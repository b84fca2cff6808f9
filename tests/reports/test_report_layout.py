"""The report's layout as a reader sees it: levels, labels, wrapping, fonts, charts."""

import subprocess
import xml.etree.ElementTree as ET

import pytest

from events.selectors.labels import segment_label
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from tests.support.pdf import flat, page_count, pdf_text
from tests.support.scenario import build_scenario

LONG_URL = "https://example.org/field-tests/" + "x" * 90
TEXT = f"Trecker 🚜 שלום עולם مرحبا {LONG_URL}"


@pytest.fixture
def wide_scenario(vehicle, other_vehicle, performer, media_root):
    return build_scenario(vehicle, other_vehicle, performer, text=TEXT)


@pytest.fixture
def reports(wide_scenario, tmp_path):
    """One PDF per level, without tiles (as offline in the field)."""
    return {
        level: render_report(wide_scenario.event, ReportOptions(no_tiles=True, level=level)).pdf
        for level in ("summary", "standard", "full")
    }


def _write(pdf: bytes, tmp_path, name: str):
    path = tmp_path / name
    path.write_bytes(pdf)
    return path


def test_levels_show_no_segment_ito_blocks_or_every_segment(reports, wide_scenario, tmp_path):
    pages = {level: page_count(pdf, tmp_path) for level, pdf in reports.items()}
    assert pages["summary"] < pages["standard"] < pages["full"]
    text = {level: flat(pdf_text(pdf, tmp_path)) for level, pdf in reports.items()}
    m = wide_scenario.masters
    for key in ("A1", "I1", "A3", "I2", "A4", "I3"):
        title = f"{segment_label(m[key])} · {m[key].segment_type_id.upper()} at"
        assert title not in text["summary"], key
        assert (title in text["standard"]) == (m[key].segment_type_id == "ito"), key
        assert title in text["full"], key
    assert "Interventions (ITO segments)" in text["standard"]


def test_segments_carry_the_gui_label_and_no_database_numbering(reports, wide_scenario, tmp_path):
    text = flat(pdf_text(reports["full"], tmp_path))
    i1 = wide_scenario.masters["I1"]
    assert segment_label(i1) == "Leg 1 · #2"
    assert f"Segment {segment_label(i1)}" in text
    assert f"(id {i1.id})" not in text


def test_nothing_runs_outside_the_page_box(reports, tmp_path):
    path = _write(reports["full"], tmp_path, "full.pdf")
    out = subprocess.run(["pdftotext", "-bbox", str(path), "-"], capture_output=True, check=True)
    out = out.stdout.decode(errors="replace")
    root = ET.fromstring(out.replace("&nbsp;", " ").split("<body>", 1)[1].rsplit("</body>", 1)[0])
    words = 0
    for page in root.iter("page"):
        width, height = float(page.get("width")), float(page.get("height"))
        for word in page.iter("word"):
            words += 1
            assert 0 <= float(word.get("xMin")) and float(word.get("xMax")) <= width, word.text
            assert 0 <= float(word.get("yMin")) and float(word.get("yMax")) <= height, word.text
    assert words > 500
    # The long URL is all there, wrapped over lines rather than cut.
    assert "x" * 90 in flat(pdf_text(reports["full"], tmp_path)).replace(" ", "").replace(
        "\u200b", ""
    )


def test_emoji_and_right_to_left_text_render(reports, tmp_path):
    path = _write(reports["full"], tmp_path, "fonts.pdf")
    fonts = subprocess.run(["pdffonts", str(path)], capture_output=True).stdout
    fonts = fonts.decode(errors="replace")
    # Noto Color Emoji's glyphs are pictures: typst embeds them as a Type 3 font.
    assert "Type 3" in fonts
    assert "DejaVuSans" in fonts
    text = pdf_text(reports["full"], tmp_path)
    assert "🚜" in text
    assert "שלום" in text or "םולש" in text
    assert "مرحبا" in text or "ابحرم" in text


def test_charts_have_titles_units_and_linear_axes(reports, tmp_path):
    text = flat(pdf_text(reports["summary"], tmp_path))
    for title in (
        "Distance per shift: autonomous and manual",
        "Interventions per shift by reason",
        "MDBI per shift with 90 % bounds",
        "MTBI per shift with 90 % bounds",
    ):
        assert title in text, title
    for unit in ("distance [m]", "interventions [count]", "MDBI [m]", "MTBI [h]"):
        assert unit in text, unit
    # A log axis would print powers of ten.
    assert "×10" not in text and "10¹" not in text


def test_tiles_unavailable_is_said_once_per_map(wide_scenario, tmp_path):
    result = render_report(
        wide_scenario.event, ReportOptions(tile_url="http://127.0.0.1:9/{z}/{x}/{y}.png")
    )
    text = flat(pdf_text(result.pdf, tmp_path))
    # Two shifts, one overview map each; segment sketches carry no tiles.
    assert text.count("Map tiles unavailable") == 2
