"""Each shift's timeline shows the weather of its legs as a symbol and a name."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace
from zoneinfo import ZoneInfo

import numpy as np
from PIL import Image

from reports.charts import weather
from reports.charts.timeline import draw_timeline
from reports.documents import sections
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions

T0 = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)


def runs():
    def run(kind, start, end):
        return SimpleNamespace(
            kind=kind,
            start=T0 + timedelta(minutes=start),
            end=T0 + timedelta(minutes=end),
            is_open=False,
            reasons=[],
        )

    return [run("auto", 0, 5), run("ito", 5, 7), run("auto", 7, 20)]


def pixels_near(path, colour: str, tolerance: int = 30) -> int:
    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    target = np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(image - target).max(axis=2) <= tolerance).sum())


def draw(tmp_path, changes) -> str:
    path = str(tmp_path / f"timeline-{len(list(tmp_path.iterdir()))}.png")
    return draw_timeline(runs(), {}, changes, ZoneInfo("Europe/Berlin"), path)


def test_a_sunny_leg_shows_a_sun_and_a_rainy_one_does_not(tmp_path):
    sunny = draw(tmp_path, [(T0, "sunny", "sun")])
    rainy = draw(tmp_path, [(T0, "rainy", "rain")])
    plain = draw(tmp_path, [])
    assert pixels_near(sunny, weather.SUN) > 50
    assert pixels_near(rainy, weather.SUN) == 0 and pixels_near(plain, weather.SUN) == 0
    # The rain symbol's cloud is dark grey; a timeline without weather has none.
    assert pixels_near(rainy, weather.CLOUD_DARK, 4) > 100
    assert pixels_near(plain, weather.CLOUD_DARK, 4) == 0


def test_every_catalogue_symbol_is_distinct_and_an_unknown_one_is_a_question_mark(tmp_path):
    from events.seeds import WEATHER

    pictures = {
        icon: np.asarray(Image.open(draw(tmp_path, [(T0, "x", icon)])).convert("RGB"))
        for *_, icon in WEATHER
    }
    pictures["?"] = np.asarray(Image.open(draw(tmp_path, [(T0, "x", "")])).convert("RGB"))
    names = list(pictures)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            assert not np.array_equal(pictures[a], pictures[b]), (a, b)


def test_the_report_gives_each_shift_its_legs_weather(scenario, settings, tmp_path, monkeypatch):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    seen = []
    real = sections.draw_timeline

    def recording(shift_runs, reasons, weather_changes, *args, **kwargs):
        seen.append([(label, icon) for _, label, icon in weather_changes])
        return real(shift_runs, reasons, weather_changes, *args, **kwargs)

    monkeypatch.setattr(sections, "draw_timeline", recording)
    render_report(scenario.event, ReportOptions(no_tiles=True))
    assert seen == [[("sunny", "sun")], [("rainy", "rain")]]
