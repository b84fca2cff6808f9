"""The PDF report in the test event's language, or the one --language asks for."""

import re

from django.core.management import call_command

from tests.support.pdf import flat, pdf_text


def _report(event, tmp_path, *extra) -> str:
    out = tmp_path / f"report{len(extra)}.pdf"
    call_command(
        "ftt_report", "--test-event", str(event.pk), "--no-tiles", "--level", "summary",
        "-o", str(out), *extra,
    )  # fmt: skip
    return flat(pdf_text(out.read_bytes(), tmp_path))


def test_the_report_speaks_the_test_events_language_unless_asked_otherwise(
    scenario, tmp_path, settings
):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    scenario.event.language = "de"
    scenario.event.save(update_fields=["language"])
    german = _report(scenario.event, tmp_path)
    assert "Globale Statistik" in german and "Schicht 1" in german
    assert "Global statistics" not in german
    # Decimal comma and day.month.year, as a German reader writes them.
    assert re.search(r"\d+,\d\d m\b", german)
    assert re.search(r"\b\d\d\.\d\d\.20\d\d \d\d:\d\d:\d\d\b", german)
    english = _report(scenario.event, tmp_path, "--language", "en")
    assert "Global statistics" in english and "Shift 1" in english
    assert "Schicht" not in english
    assert re.search(r"\d+\.\d\d m\b", english) and not re.search(r"\d+,\d\d m\b", english)
