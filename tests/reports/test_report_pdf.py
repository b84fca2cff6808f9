"""The PDF as a reader sees it: every figure of the scenario, checked by hand.

Expected values come from the scenario's geometry (scenario.py) and printed
chi-square tables, written in the report's units: metres with 2 decimals,
H:MM:SS, percent with 1 decimal, rates with 3 decimals.
"""

import subprocess

import pytest

from events.selectors.labels import segment_label
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from telemetry.models import Pose
from telemetry.services.segment_figures import recount_figures
from tests.support.pdf import flat, has_row, page_count, pdf_text, save_pages
from tests.support.scenario import CHI2_05, CHI2_95, HOSTILE, STEP_M, T0


def m(steps: float) -> str:
    return f"{steps * STEP_M:.2f} m"


def hms(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


@pytest.fixture
def tile_cache(settings, tmp_path):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    return settings.FTT_TILE_CACHE


@pytest.fixture
def report(scenario, tile_server, tile_cache, tmp_path):
    options = ReportOptions(
        name=f"Report {HOSTILE}",
        version="2.1-β",
        recipient=f"Kunde {HOSTILE}",
        recipient_address=["Fraunhoferstraße 20", "53343 Wachtberg"],
        creator="東京チーム",
        creator_address=["1-2-3 Chiyoda, 東京"],
        tile_url=tile_server.url,
    )
    result = render_report(scenario.event, options)
    return result, pdf_text(result.pdf, tmp_path)


@pytest.fixture
def report_flow_text(report, tmp_path):
    return flat(pdf_text(report[0].pdf, tmp_path, layout=False))


def test_event_figures_equal_the_hand_computed_values(report):
    _, text = report
    t_a, t_m = 940, 160
    assert has_row(text, "Total distance", m(17))
    assert has_row(text, "Autonomous distance", m(13))
    assert has_row(text, "Manual (ITO) distance", m(4))
    assert has_row(text, "Autonomy by distance", f"{100 * 13 / 17:.1f} %")
    assert has_row(text, "Autonomous time", hms(t_a))
    assert has_row(text, "Manual (ITO) time", hms(t_m))
    assert has_row(text, "Autonomy by time", f"{100 * t_a / (t_a + t_m):.1f} %")
    assert has_row(text, "Mean autonomous run", m(13 / 4))
    assert has_row(text, "Longest autonomous run", m(4))
    assert has_row(text, "Interventions", "2")
    assert has_row(text, "MDBI", m(13 / 2))
    lower, upper = 2 * 13 / CHI2_95[6], 2 * 13 / CHI2_05[4]
    assert has_row(text, "MDBI 90 % bounds", f"{m(lower)} – {m(upper)}")
    assert has_row(text, "MTBI", hms(t_a / 2))
    assert has_row(
        text, "MTBI 90 % bounds", f"{hms(2 * t_a / CHI2_95[6])} – {hms(2 * t_a / CHI2_05[4])}"
    )
    assert has_row(text, "Interventions per km", f"{2 / (13 * STEP_M / 1000):.3f}")
    assert has_row(text, "Interventions per hour", f"{2 / (t_a / 3600):.3f}")


def test_per_shift_tables_and_reasons(report):
    _, text = report
    # Distance log: total, autonomous, share by distance and by time, mean and max run.
    share_1, share_2 = f"{100 * 340 / 400:.1f} %", f"{100 * 600 / 700:.1f} %"
    assert has_row(text, "Shift 1", "Husky A200", "sunny", m(6), m(5), "83.3 %", share_1)
    assert has_row(text, m(2.5), m(3))
    assert has_row(text, "Shift 2", "Jackal", "rainy", m(11), m(8), "72.7 %", share_2, m(4), m(4))
    # Reliability: one intervention each.
    assert has_row(
        text,
        "Shift 1",
        "1",
        m(5),
        f"{m(2 * 5 / CHI2_95[4])} – {m(2 * 5 / CHI2_05[2])}",
        hms(340),
        f"{hms(2 * 340 / CHI2_95[4])} – {hms(2 * 340 / CHI2_05[2])}",
        f"{1 / (5 * STEP_M / 1000):.3f}",
        f"{1 / (340 / 3600):.3f}",
    )
    assert has_row(text, "Shift 2", "1", m(8), f"{m(2 * 8 / CHI2_95[4])} – {m(2 * 8 / CHI2_05[2])}")
    # Reasons: counted or not, interventions, manual time.
    assert has_row(text, "Safety", "yes", "1", hms(60))
    assert has_row(text, "Planner", "yes", "1", hms(40))
    assert has_row(text, "Goal reached", "no", "0", hms(30))
    assert has_row(text, "Unexpected", "yes", "1", hms(70))
    # Auto/ITO table of shift 1: runs, interventions, time, distance, speed.
    assert has_row(text, "AUTO", "2", "–", hms(340), m(5), f"{5 * STEP_M / 340:.2f} m/s")
    assert has_row(text, "ITO", "1", "1", hms(60), m(1), f"{STEP_M / 60:.2f} m/s")


def test_segments_show_times_in_the_event_time_zone_and_their_distances(report):
    _, text = report
    # Shift 1 starts 01:00 UTC, which is 10:00 in Tokyo.
    assert "Shift 1: 2026-03-02 10:00:00 – 2026-03-02 10:06:40" in text
    assert "Shift 2: 2026-03-02 11:00:00 – 2026-03-02 11:11:40" in text
    for duration, steps in ((100, 3), (60, 1), (240, 2), (300, 4), (30, 2), (70, 1)):
        assert has_row(text, "Duration", hms(duration)), duration
        assert has_row(text, "Distance", m(steps)), steps
    assert has_row(text, "Reason(s)", "Safety (counted), Planner (counted)")
    assert has_row(text, "Reason(s)", "Goal reached")


def test_people_appear_in_their_own_roles(report, scenario):
    text = flat(report[1])
    for role, key in (
        ("Test director", "director"),
        ("Test administrator", "admin"),
        ("Robot operator", "operator"),
        ("Safety officer", "safety"),
    ):
        name = scenario.people[key].name
        assert f"{role} {flat(name)}" in text, role


def test_hostile_and_non_ascii_text_renders_literally_in_every_field(report, report_flow_text):
    table_text = flat(report[1])
    hostile = flat(HOSTILE)
    for field in (
        f"Location Field {hostile}",
        f"Software version {hostile}",
        f"Test intent {hostile}",
        f"Obstacle {hostile}",
        f"Lighting {hostile}",
        f"Slope {hostile}",
        f"note {hostile}",
    ):
        assert field in table_text or field in report_flow_text, field
    # The camera frame's caption under its thumbnail and in the image appendix.
    assert f": {hostile} (back to the segment)" in report_flow_text
    # The title page's two columns read best one after the other.
    for field in (
        f"Report {hostile}",
        f"Kunde {hostile}",
        "Fraunhoferstraße 20 53343 Wachtberg",
        "東京チーム 1-2-3 Chiyoda, 東京",
        "Version 2.1-β",
    ):
        assert field in report_flow_text, field


def test_cjk_and_latin_fonts_are_embedded(report, tmp_path):
    result, _ = report
    path = tmp_path / "fonts.pdf"
    path.write_bytes(result.pdf)
    fonts = subprocess.run(["pdffonts", str(path)], capture_output=True, text=True).stdout
    assert "DejaVuSans" in fonts
    assert "WenQuanYi" in fonts or "NotoSansCJK" in fonts


def test_methods_appendix_lists_reasons_formulas_and_gaps(report, scenario):
    _, raw = report
    text = flat(raw)
    assert "Counted: Apparatus, Maintenance, Manual transit, Other, Planner, Safety" in text
    assert "Not counted: End of shift, Goal reached, Non-Stop" in text
    assert "MDBI = D_a / I" in text
    assert "lower = 2E / chi2(0.95; 2I + 2), upper = 2E / chi2(0.05; 2I)" in text
    i2 = scenario.masters["I2"]
    assert f"Shift 2, {segment_label(i2)} (ITO)" in text  # the segment without poses
    # A3 has 20 s between its second and third pose (gap threshold 10 s).
    assert "11:00:20 – 11:00:40 (0:00:20)" in text
    assert "Map tiles: http://127.0.0.1" in text
    assert "the stored start): 1, at most 0.8 s" in text  # A4's mode message had no stamp
    assert "from gaps in the robot’s stamps): 12" in text  # leg 2's collector lost 12 fixes


def test_pages_are_rendered_as_png_artifacts(report, tmp_path):
    result, _ = report
    pages = save_pages(result.pdf, "synthetic")
    assert len(pages) == page_count(result.pdf, tmp_path) > 5
    assert all(p.stat().st_size > 1000 for p in pages)


def test_open_segments_make_the_report_provisional(open_scenario, tmp_path, tile_cache):
    result = render_report(open_scenario, ReportOptions(no_tiles=True))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert result.provisional
    assert "PROVISIONAL: the test event has open segments" in text
    assert "(still open)" in text
    assert "Open segment: its figures are provisional." in text
    save_pages(result.pdf, "open-segments")


def test_event_without_poses_still_reports_times_and_lists_the_gaps(scenario, tmp_path, tile_cache):
    # Poses removed behind the services' back; their stored figures are set right as
    # an administrator would (ftt_recount_figures --fix).
    Pose.objects.all().delete()
    recount_figures([seg.pk for seg in scenario.masters.values()], fix=True)
    result = render_report(scenario.event, ReportOptions(no_tiles=True))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert "Autonomous time 0:15:40" in text
    for name, seg in scenario.masters.items():
        assert f"{segment_label(seg)} ({seg.segment_type_id.upper()}) (" in text, name
    assert "Positions without a GPS fix (left out): 0" in text
    save_pages(result.pdf, "no-poses")


def test_unreachable_tile_server_gives_plain_maps_and_says_so(
    scenario, dead_tile_url, tmp_path, tile_cache
):
    result = render_report(scenario.event, ReportOptions(tile_url=dead_tile_url))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert not result.tiles_used
    assert "Map tiles were unavailable (tile server unreachable)" in text
    # Distances do not depend on the background.
    assert f"Total distance {m(17)}" in text
    save_pages(result.pdf, "no-tiles")


def test_tiles_are_fetched_politely_and_reused_from_the_cache(scenario, tile_server, tile_cache):
    render_report(scenario.event, ReportOptions(tile_url=tile_server.url))
    first = len(tile_server.requests)
    assert first > 0
    assert all(agent.startswith("FTT-field-test-report/") for _, agent in tile_server.requests)
    # Each tile is requested once, and a second report needs none at all.
    assert len({path for path, _ in tile_server.requests}) == first
    render_report(scenario.event, ReportOptions(tile_url=tile_server.url))
    assert len(tile_server.requests) == first


def test_empty_shift_and_unreadable_image_do_not_stop_the_report(
    scenario, vehicle, tmp_path, tile_cache
):
    from events.services import logs
    from telemetry.models import Image

    empty = logs.create_shift(test_event=scenario.event, vehicle=vehicle, at=T0)
    image = Image.objects.get()
    image.image.open("wb").write(b"not an image")  # e.g. a truncated upload
    image.image.close()
    result = render_report(scenario.event, ReportOptions(no_tiles=True))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert f"Shift {empty.number}: 2026-03-02 10:00:00 – open" in text
    assert "No segments in this shift." in text
    assert f"Image {image.pk} unreadable" in text  # listed under warnings
    assert f"Total distance {m(17)}" in text


def test_per_vehicle_reliability_contents_and_note_authors(report, scenario):
    _, raw = report
    # Each vehicle drove one shift here, so its row repeats that shift's figures.
    assert has_row(
        raw, "Husky A200", "1", m(5), f"{m(2 * 5 / CHI2_95[4])} – {m(2 * 5 / CHI2_05[2])}"
    )
    assert has_row(raw, "Jackal", "1", m(8), f"{m(2 * 8 / CHI2_95[4])} – {m(2 * 8 / CHI2_05[2])}")
    text = flat(raw)
    assert text.index("Contents") < text.index("Global statistics")
    for heading in ("Global statistics", "Per vehicle", "Reasons: interventions and manual time"):
        assert text.count(heading) >= 2, heading  # in the outline and as a heading
    author = flat(scenario.people["operator"].name)
    assert f"{author} (" in text and f"note {flat(HOSTILE)}" in text


def test_progress_is_reported_in_order_up_to_done(scenario, tile_cache):
    steps = []
    render_report(
        scenario.event, ReportOptions(no_tiles=True), lambda f, msg: steps.append((f, str(msg)))
    )
    fractions = [f for f, _ in steps]
    assert fractions == sorted(fractions) and len(steps) >= 4
    assert steps[-1] == (1.0, "done") and 0.0 <= fractions[0] < 0.5
    assert any("typesetting" in msg for _, msg in steps)
