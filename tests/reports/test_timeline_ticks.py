"""A timeline's time axis never writes the same tick label twice."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace
from zoneinfo import ZoneInfo

import pytest

from reports.figures import timeline

T0 = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)


@pytest.mark.parametrize(
    "span", [timedelta(minutes=2), timedelta(minutes=40), timedelta(hours=9), timedelta(days=3)]
)
def test_tick_labels_are_distinct(tmp_path, monkeypatch, span):
    drawn = []
    monkeypatch.setattr(timeline.plt, "close", drawn.append)
    runs = [
        SimpleNamespace(kind=kind, start=start, end=end, is_open=False, reasons=[])
        for kind, start, end in (
            ("auto", T0, T0 + span / 2),
            ("ito", T0 + span / 2, T0 + span),
        )
    ]
    timeline.draw_timeline(runs, {}, [], ZoneInfo("Europe/Berlin"), str(tmp_path / "t.png"))
    labels = [label.get_text() for label in drawn[0].axes[0].get_xticklabels()]
    assert len(labels) >= 3 and all(labels)
    assert len(set(labels)) == len(labels), labels
