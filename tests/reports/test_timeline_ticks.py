"""A timeline's time axis never writes the same tick label twice."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace
from zoneinfo import ZoneInfo

import pytest

from reports.charts import timeline

T0 = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)


def _labels(tmp_path, monkeypatch, start, span) -> list[str]:
    drawn = []
    monkeypatch.setattr(timeline.plt, "close", drawn.append)
    runs = [
        SimpleNamespace(kind=kind, start=start, end=end, is_open=False, reasons=[])
        for kind, start, end in (
            ("auto", start, start + span / 2),
            ("ito", start + span / 2, start + span),
        )
    ]
    timeline.draw_timeline(runs, {}, [], ZoneInfo("Europe/Berlin"), str(tmp_path / "t.png"))
    return [label.get_text() for label in drawn[0].axes[0].get_xticklabels()]


@pytest.mark.parametrize(
    "span", [timedelta(minutes=2), timedelta(minutes=40), timedelta(hours=9), timedelta(days=3)]
)
def test_tick_labels_are_distinct(tmp_path, monkeypatch, span):
    labels = _labels(tmp_path, monkeypatch, T0, span)
    assert len(labels) >= 3 and all(labels)
    assert len(set(labels)) == len(labels), labels


@pytest.mark.parametrize("span", [timedelta(minutes=200), timedelta(minutes=400)])
def test_a_night_the_clocks_go_forward_writes_each_tick_once(tmp_path, monkeypatch, span):
    # 22:00 UTC on 28 March 2026 is 23:00 in Berlin; at 02:00 the clocks go to 03:00.
    labels = _labels(tmp_path, monkeypatch, datetime(2026, 3, 28, 22, 0, tzinfo=UTC), span)
    assert "01:00" in labels and "03:00" in labels and "02:00" not in labels
    assert len(set(labels)) == len(labels), labels
