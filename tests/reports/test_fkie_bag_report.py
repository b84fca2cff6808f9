"""The original tool's sample recording, imported through the collector's bag
reader, gives a complete report.  The original report measured 223.0 m over
its five segments; our geodesic over time-ordered poses (collector thinning
on the robot clock) agrees within 1 %."""

import re
from datetime import UTC, datetime

import pytest
from django.db.models import Max

from events.models import Segment
from events.services import logs
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from reports.selectors.statistics import event_statistics
from rosbridge_app.collector.bag import bag_events
from rosbridge_app.collector.event_writer import write_events
from tests.support.fkie import FKIE_BAG
from tests.support.pdf import flat, pdf_text, save_pages


@pytest.fixture
def fkie_event(vehicle, media_root):
    if not FKIE_BAG.exists():
        pytest.skip("fkie_test.bag not available")
    start = datetime(2019, 4, 8, tzinfo=UTC)
    event = logs.create_test_event(location="FKIE Wachtberg", time_zone="Europe/Berlin", at=start)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, at=start)
    leg = logs.create_leg(shift=shift, at=start, weather_id="sunny")
    write_events(leg, bag_events(FKIE_BAG, {"params.robot_mode_type": "industrial"}))
    last = Segment.objects.filter(leg=leg).aggregate(Max("end"))["end__max"]
    return logs.close_test_event(event, at=last)


def test_fkie_bag_gives_a_complete_report(fkie_event, tmp_path, settings):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    stats = event_statistics(fkie_event)
    assert [r.kind for r in stats.runs] == ["ito", "auto", "ito", "auto", "ito"]
    assert stats.overall.total_distance == pytest.approx(223.0, rel=0.01)

    result = render_report(fkie_event, ReportOptions(name="fkie_test.bag", no_tiles=True))
    text = flat(pdf_text(result.pdf, tmp_path))
    assert not result.provisional
    # The bag was recorded from about 14:12 to 14:16 UTC: 16:1x in Berlin summer time.
    assert re.search(r"Shift 1: 2019-04-08 02:00:00 – 2019-04-08 16:1\d:\d\d", text)
    total = float(re.search(r"Total distance ([\d.]+) m", text).group(1))
    assert total == pytest.approx(stats.overall.total_distance, abs=0.01)
    titles = re.findall(r"(Leg \d+ · #\d+) · (?:AUTO|ITO) at", text)
    assert titles == [f"Leg 1 · #{n}" for n in range(1, 6)]
    # Counted: the bag's take-overs are 'unassigned', which counts.
    assert "Interventions 3" in text
    save_pages(result.pdf, "fkie-bag")
