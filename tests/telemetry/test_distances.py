"""One distance per segment: the GUI, the API, the statistics and the CSV agree.

The leg below has a start position on every master, poses on the AUTO runs
only, and a following master after each but the last, so each of the three
parts of the rule (start, poses, next start) changes the figure.
"""

import csv
import io
from datetime import UTC, datetime, timedelta

import pytest
from pyproj import Geod

from events.models import SegmentType
from events.services import segments
from events.services.segments import GpsPosition
from reports.selectors.exports import segments_csv
from reports.selectors.statistics import event_runs
from telemetry.services import recording
from telemetry.services.recording import GpsFix

pytestmark = pytest.mark.django_db

T0 = datetime(2026, 6, 1, 9, 0, tzinfo=UTC)
GEOD = Geod(ellps="WGS84")


def _at(seconds):
    return T0 + timedelta(seconds=seconds)


def _length(lons):
    _, _, steps = GEOD.inv(lons[:-1], [0.0] * (len(lons) - 1), lons[1:], [0.0] * (len(lons) - 1))
    return sum(steps)


@pytest.fixture
def drive(leg):
    """AUTO from 0.000 with poses to 0.002; ITO at 0.0021 without poses; AUTO
    from 0.0025 with poses to 0.004 (open, nothing follows)."""
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])
    a1 = segments.report_mode(leg, SegmentType.AUTO, at=_at(0), gps=GpsPosition(0.0, 0.0)).master
    recording.record_poses(
        a1, [GpsFix(0.001, 0.0, robot_stamp=_at(10)), GpsFix(0.002, 0.0, robot_stamp=_at(20))]
    )
    i1 = segments.report_mode(leg, SegmentType.ITO, at=_at(30), gps=GpsPosition(0.0021, 0.0)).master
    a2 = segments.report_mode(
        leg, SegmentType.AUTO, at=_at(60), gps=GpsPosition(0.0025, 0.0)
    ).master
    recording.record_poses(
        a2, [GpsFix(0.003, 0.0, robot_stamp=_at(70)), GpsFix(0.004, 0.0, robot_stamp=_at(80))]
    )
    return {
        "A1": (a1, _length([0.0, 0.001, 0.002, 0.0021])),
        "I1": (i1, _length([0.0021, 0.0025])),
        "A2": (a2, _length([0.0025, 0.003, 0.004])),
    }


def test_gui_api_statistics_and_csv_give_the_same_distance(drive, leg, client, role_user):
    client.force_login(role_user("viewer"))
    gui = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["segments"]
    api = client.get(f"/api/tracks/?leg={leg.pk}").json()["features"]
    api_by_id = {f["id"]: f["properties"]["distance_m"] for f in api}
    event = leg.shift.test_event
    runs = {run.id: run.distance for run in event_runs(event)}
    rows = csv.DictReader(io.StringIO(segments_csv(event)))
    csv_by_id = {int(r["segment_id"]): float(r["distance_m"]) for r in rows if r["distance_m"]}

    for name, (segment, expected) in drive.items():
        figures = {
            "gui": gui[str(segment.pk)]["distance_m"],
            "statistics": runs[segment.pk],
            "csv": csv_by_id[segment.pk],
        }
        if segment.segment_type_id == SegmentType.AUTO:
            # The API lists segments that have poses; I1 has none.
            figures["api"] = api_by_id[segment.pk]
        for source, value in figures.items():
            assert value == pytest.approx(expected, abs=1e-3), (name, source, figures)


def test_a_segment_with_nothing_measured_shows_no_distance(leg, client, role_user):
    """No start position, no poses, nothing after it: "—", not 0 m."""
    master = segments.report_mode(leg, SegmentType.AUTO).master
    client.force_login(role_user("viewer"))
    gui = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["segments"]
    assert gui[str(master.pk)]["distance_m"] is None
