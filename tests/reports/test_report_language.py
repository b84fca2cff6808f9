"""The PDF report in the test event's language, or the one --language asks for."""

import math
import re

import pytest
from django.core.management import call_command
from django.utils import translation

from reports.documents.wording import comparison_text, report_text
from reports.models import Report
from reports.services.generation import run_job
from tests.support.pdf import flat, pdf_text
from tests.support.scenario import build_scenario


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


def _english_words(wording) -> set[str]:
    """The fixed words of a template that read differently in German (placeholders
    left out): none of them may stay in a German PDF."""
    with translation.override("en"):
        english = wording()
    with translation.override("de"):
        german = wording()
    return {
        text
        for key, text in english.items()
        if key != "lang" and text != german[key] and "%(" not in text
    }


# Chart titles and axis words: the charts keep their text as text in the PDF.
CHART_WORDS = {
    "Distance per shift",
    "Interventions per shift by reason",
    "per shift with 90 % bounds",
    "Reliability growth: cumulative interventions",
    "cumulative autonomous distance",
    "Take-over hotspots: where interventions started",
    "observed",
}


def test_a_german_report_keeps_no_english_words(scenario, tmp_path, settings):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    scenario.event.language = "de"
    scenario.event.save(update_fields=["language"])
    out = tmp_path / "full.pdf"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--no-tiles", "-o", str(out))
    german = flat(pdf_text(out.read_bytes(), tmp_path))
    left = {w for w in _english_words(report_text) | CHART_WORDS if w in german}
    assert left == set()
    assert "Herkunft" in german and "Methoden und Datenqualität" in german
    assert "Strecke je Schicht: autonom und manuell" in german  # a chart's title


@pytest.fixture
def two_events(vehicle, other_vehicle, performer, media_root):
    first = build_scenario(vehicle, other_vehicle, performer, text="v1")
    second = build_scenario(vehicle, other_vehicle, performer, text="v2")
    return first, second


def _comparison(events, tmp_path, *extra) -> str:
    out = tmp_path / f"cmp{len(extra)}.pdf"
    ids = [str(e.event.pk) for e in events]
    call_command("ftt_report", "--compare", *ids, "-o", str(out), *extra)
    return flat(pdf_text(out.read_bytes(), tmp_path))


def test_the_comparison_speaks_the_language_its_test_events_share(two_events, tmp_path):
    for scenario in two_events:
        scenario.event.language = "de"
        scenario.event.save(update_fields=["language"])
    first = two_events[0].event
    day = first.start.astimezone(first.tzinfo).date()
    beta = 4 / sum(math.log(26 / t) for t in (3, 13, 16, 26))
    german = _comparison(two_events, tmp_path)
    assert "Zuverlässigkeit über Testveranstaltungen" in german
    assert "Übernahme-Schwerpunkte: wo Eingriffe begannen" in german  # the chart
    left = {w for w in _english_words(comparison_text) | CHART_WORDS if w in german}
    assert left == set()
    # Figures with a decimal comma, days and the build time as day.month.year.
    assert f"Wachstumsparameter 1 − β {1 - beta:.3f}".replace(".", ",") in german
    assert re.search(r"\d+,\d\d m\b", german) and not re.search(r"\d+\.\d\d m\b", german)
    assert f"{day:%d.%m.%Y}" in german and f"{day:%Y-%m-%d}" not in german
    assert re.search(r"\b\d\d\.\d\d\.20\d\d \d\d:\d\d:\d\d\b", german)
    english = _comparison(two_events, tmp_path, "--language", "en")
    assert "Reliability across test events" in english and "Zuverlässigkeit" not in english
    assert f"Growth parameter 1 − β {1 - beta:.3f}" in english
    assert f"{day:%Y-%m-%d}" in english and not re.search(r"\d+,\d\d m\b", english)


def test_a_comparison_of_mixed_languages_is_in_the_sites(two_events, tmp_path, settings):
    two_events[0].event.language = "de"
    two_events[0].event.save(update_fields=["language"])
    settings.LANGUAGE_CODE = "en"
    text = _comparison(two_events, tmp_path)
    assert "Reliability across test events" in text and "Zuverlässigkeit" not in text


def test_a_comparison_job_takes_the_language_asked_for(two_events, api_client, tmp_path):
    operator = api_client("operator")
    ids = [s.event.pk for s in two_events]
    refused = operator.post(
        "/api/reports/", {"compare": ids, "options": {"language": "xx"}}, format="json"
    )
    assert refused.status_code == 400 and "options" in refused.json()["errors"]
    asked = operator.post(
        "/api/reports/", {"compare": ids, "options": {"language": "de"}}, format="json"
    )
    assert asked.status_code == 202
    report = run_job(asked.json()["id"])
    assert report.status == Report.Status.DONE, report.error
    text = flat(pdf_text(report.pdf.read(), tmp_path))
    assert "Zuverlässigkeit über Testveranstaltungen" in text


def _ticks(text: str, after: str, before: str) -> list[str]:
    """The numbers a chart's axes show, read from the PDF between two of its words."""
    chart = text[text.index(after) + len(after) : text.index(before)]
    return re.findall(r"(?<![\w.,])\d+[.,]?\d*(?![\w.,])", chart)


def test_chart_ticks_have_the_decimal_comma_in_german(two_events, tmp_path):
    for scenario in two_events:
        scenario.event.language = "de"
        scenario.event.save(update_fields=["language"])
    german = _comparison(two_events, tmp_path)
    # The growth chart's axes: cumulative interventions and kilometres, both in halves.
    ticks = _ticks(german, "Zuverlässigkeitswachstum: kumulierte Eingriffe", "[km]")
    assert "0,5" in ticks and "1,5" in ticks, ticks
    assert not [t for t in ticks if "." in t], ticks
    assert "Crow-AMSAA, β = 1,20" in german
    english = _comparison(two_events, tmp_path, "--language", "en")
    ticks = _ticks(english, "Reliability growth: cumulative interventions", "[km]")
    assert "0.5" in ticks and not [t for t in ticks if "," in t], ticks
