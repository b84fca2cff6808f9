"""The original's min_dur and zoom_level: a minimum timeline length and a closest zoom."""

import re
from datetime import UTC, datetime, timedelta

import pytest
from django.core.management import CommandError, call_command

from reports.charts.timeline import time_axis
from reports.documents import sections
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from reports.models import Report


@pytest.fixture
def tile_cache(settings, tmp_path):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    return settings.FTT_TILE_CACHE


def zooms(tile_server) -> set[int]:
    return {int(re.match(r"/(\d+)/", path).group(1)) for path, _ in tile_server.requests}


def test_a_short_shift_is_drawn_over_the_minimum_timeline_length():
    first = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)
    last = first + timedelta(minutes=10)
    start, end = time_axis(first, last)
    assert timedelta(minutes=10) < end - start < timedelta(minutes=11)
    start, end = time_axis(first, last, min_span=timedelta(hours=2))
    assert start < first and end - start >= timedelta(hours=2)
    # A shift longer than the minimum keeps its own length.
    start, end = time_axis(first, first + timedelta(hours=3), min_span=timedelta(hours=2))
    assert timedelta(hours=3) < end - start < timedelta(hours=3, minutes=10)


def test_the_report_draws_every_timeline_with_the_minimum_length(scenario, tile_cache, monkeypatch):
    spans = []
    draw = sections.draw_timeline

    def recording_draw(*args, **kwargs):
        spans.append(kwargs["min_span"])
        return draw(*args, **kwargs)

    monkeypatch.setattr(sections, "draw_timeline", recording_draw)
    render_report(scenario.event, ReportOptions(no_tiles=True, min_timeline_hours=1.5))
    assert spans and all(span == timedelta(hours=1.5) for span in spans)


def test_tiles_are_never_closer_than_the_maximum_zoom(scenario, tile_server, tile_cache):
    render_report(scenario.event, ReportOptions(tile_url=tile_server.url))
    fitted = zooms(tile_server)
    assert max(fitted) > 12  # the scenario's tracks are a few hundred metres long
    tile_server.requests.clear()
    render_report(scenario.event, ReportOptions(tile_url=tile_server.url, max_zoom=12))
    capped = zooms(tile_server)
    assert capped and max(capped) <= 12


def test_out_of_range_options_are_refused_with_field_messages(scenario, api_client):
    operator = api_client("operator")
    for options, words in (
        ({"max_zoom": 25}, "maximum map zoom"),
        ({"max_zoom": 0}, "maximum map zoom"),
        ({"max_zoom": 12.5}, "whole number"),
        ({"max_zoom": True}, "whole number"),
        ({"min_timeline_hours": -1}, "minimum timeline length"),
        ({"min_timeline_hours": "two"}, "a number"),
        ({"min_timeline_hours": 1000}, "minimum timeline length"),
    ):
        response = operator.post(
            "/api/reports/", {"test_event": scenario.event.pk, "options": options}, format="json"
        )
        assert response.status_code == 400, options
        assert words in " ".join(response.json()["errors"]["options"]), options
    assert Report.objects.count() == 0
    accepted = operator.post(
        "/api/reports/",
        {
            "test_event": scenario.event.pk,
            "options": {"no_tiles": True, "max_zoom": 15, "min_timeline_hours": 2},
        },
        format="json",
    )
    assert accepted.status_code == 202
    report = Report.objects.get()
    stored = ReportOptions.from_dict(report.options)
    assert (stored.max_zoom, stored.min_timeline_hours) == (15, 2)


def test_command_refuses_an_impossible_zoom(scenario, tmp_path):
    with pytest.raises(CommandError, match="maximum map zoom"):
        call_command(
            "ftt_report",
            "--test-event",
            str(scenario.event.pk),
            "--max-zoom",
            "30",
            "-o",
            str(tmp_path / "x.pdf"),
        )
    assert not (tmp_path / "x.pdf").exists()
