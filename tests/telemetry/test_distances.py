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
from reports.selectors.exports import segments_csv_rows
from reports.selectors.statistics import event_runs
from telemetry.selectors.distances import measured_paths, path_length
from telemetry.selectors.tracks import masters
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix
from telemetry.storage.keys import GPS_TRACK
from tests.support.modes import start_auto

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
    pose_writes.store_poses(
        a1, [GpsFix(0.001, 0.0, robot_stamp=_at(10)), GpsFix(0.002, 0.0, robot_stamp=_at(20))]
    )
    i1 = segments.report_mode(leg, SegmentType.ITO, at=_at(30), gps=GpsPosition(0.0021, 0.0)).master
    a2 = segments.report_mode(
        leg, SegmentType.AUTO, at=_at(60), gps=GpsPosition(0.0025, 0.0)
    ).master
    pose_writes.store_poses(
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
    rows = csv.DictReader(io.StringIO("".join(segments_csv_rows(event))))
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
    master = start_auto(leg)
    client.force_login(role_user("viewer"))
    gui = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["segments"]
    assert gui[str(master.pk)]["distance_m"] is None


def test_many_segments_measured_at_once_match_the_geodesic_step_by_step(leg):
    """measured_paths lays every segment's points end to end and measures them
    together; each distance must still be its own polyline's geodesic length,
    with nothing leaking across the segments' borders: an empty segment first,
    single points, a track over the antimeridian, a jump to the pole."""
    leg.start = T0 - timedelta(minutes=1)
    leg.save(update_fields=["start"])

    def run(kind, at, start=None, poses=()):
        gps = GpsPosition(*start) if start is not None else None
        master = segments.report_mode(leg, kind, at=_at(at), gps=gps).master
        fixes = [
            GpsFix(lon, lat, robot_stamp=_at(at + 1 + i)) for i, (lon, lat) in enumerate(poses)
        ]
        if fixes:
            pose_writes.store_poses(master, fixes)
        return master

    empty = run(SegmentType.AUTO, 0)
    lone_pose = run(SegmentType.ITO, 10, poses=[(179.999, 10.0)])
    antimeridian = run(
        SegmentType.AUTO, 20, (179.9995, 10.0), [(-179.9995, 10.0001), (-179.999, 10.0002)]
    )
    no_poses = run(SegmentType.ITO, 30, (-179.998, 10.0))
    polar = run(SegmentType.AUTO, 40, (0.0, 89.95), [(10.0, 89.96), (100.0, 89.96)])
    last_lone_pose = run(SegmentType.ITO, 50, poses=[(0.0, -0.5)])
    expected = {
        empty: None,
        lone_pose: [(179.999, 10.0), (179.9995, 10.0)],
        antimeridian: [
            (179.9995, 10.0),
            (-179.9995, 10.0001),
            (-179.999, 10.0002),
            (-179.998, 10.0),
        ],
        no_poses: [(-179.998, 10.0), (0.0, 89.95)],
        polar: [(0.0, 89.95), (10.0, 89.96), (100.0, 89.96)],
        last_lone_pose: None,
    }

    paths = measured_paths(list(masters(leg=leg)), GPS_TRACK)

    for master, points in expected.items():
        if points is None:
            assert paths[master.pk].distance is None, master
            continue
        lons, lats = zip(*points, strict=True)
        _, _, steps = GEOD.inv(lons[:-1], lats[:-1], lons[1:], lats[1:])
        assert paths[master.pk].distance == pytest.approx(sum(steps), rel=1e-9, abs=1e-6), master
        assert paths[master.pk].distance == path_length(lons, lats, GPS_TRACK)
