"""SpatiaLite (robot) -> PostGIS (base station) -> SpatiaLite, through archives.

The PostGIS side is this test process's database; each SpatiaLite installation
is a child process with its own data directory.
"""

import ast
import json

import pytest
from django.db import connection

from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import import_bundle
from tests.support.sites import fresh_site
from tests.support.snapshot import snapshot

# On SpatiaLite too: the export reads poses through the storage code of each database.
pytestmark = [
    pytest.mark.spatialite,
    pytest.mark.postgis_only,
    pytest.mark.django_db,
    pytest.mark.skipif(
        connection.vendor != "postgresql", reason="the base station side needs PostGIS"
    ),
]


FIGURES = ("auto_runs", "ito_runs", "interventions", "total_distance", "total_seconds")
STATISTICS = (
    "from events.models import TestEvent; "
    "from reports.selectors.statistics import event_statistics; "
    "o = event_statistics(TestEvent.objects.get()).overall; "
    f"print('FIGURES', [getattr(o, n) for n in {FIGURES!r}])"
)


def report_figures() -> list:
    from events.models import TestEvent
    from reports.selectors.statistics import event_statistics

    overall = event_statistics(TestEvent.objects.get()).overall
    return [getattr(overall, name) for name in FIGURES]


def here() -> dict:
    return json.loads(json.dumps(snapshot(names=True)))


def load(path):
    with open_archive(path) as bundle:
        return import_bundle(bundle)


def test_spatialite_to_postgis_and_back_keeps_rows_geometry_and_files(tmp_path, media_root):
    robot = fresh_site(tmp_path / "robot")
    robot.python("from tests.support.field_day import field_day; field_day()")
    robot.manage("ftt_export", str(tmp_path / "robot.zip"))
    on_robot = robot.snapshot(names=True)
    assert len(on_robot["poses"]) == 15 and len(on_robot["images"]) == 1

    plan = load(tmp_path / "robot.zip")
    assert plan.counts["poses"]["added"] == 15
    assert here() == on_robot

    export_events(tmp_path / "base.zip", select_events())
    laptop = fresh_site(tmp_path / "laptop")
    out = laptop.manage("ftt_import", str(tmp_path / "base.zip"))
    assert "Changed" in out
    assert laptop.snapshot(names=True) == on_robot


def test_robot_exports_repeatedly_to_base_station_without_duplicates(tmp_path, media_root):
    robot = fresh_site(tmp_path / "robot")
    robot.python("from tests.support.field_day import field_day; field_day(close=False)")
    robot.manage("ftt_export", str(tmp_path / "first.zip"))
    load(tmp_path / "first.zip")
    assert here() == robot.snapshot(names=True)

    # The link is down again; the robot logs on into its own database.
    robot.python("from tests.support.field_day import more_logging; more_logging()")
    robot.manage("ftt_export", str(tmp_path / "second.zip"))
    dry = robot.manage("ftt_import", "--dry-run", str(tmp_path / "second.zip"))
    assert "Would change 0 row(s)" in dry  # the robot already has all of it

    plan = load(tmp_path / "second.zip")
    assert plan.counts["legs"]["added"] == 1 and plan.counts["shifts"]["updated"] == 1
    assert plan.counts["poses"]["unchanged"] == 15 and plan.counts["poses"]["added"] == 6
    final = robot.snapshot(names=True)
    assert here() == final
    # The base station's report counts the robot's runs as the robot itself does.
    on_robot = ast.literal_eval(robot.python(STATISTICS).split("FIGURES", 1)[1].strip())
    figures = report_figures()
    assert figures[:2] == [2, 3] and figures[3] > 0
    assert figures == pytest.approx(on_robot, rel=1e-9)
    assert load(tmp_path / "second.zip").changes() == 0
    assert load(tmp_path / "first.zip").changes() == 0  # a stale archive undoes nothing
    assert here() == final


def test_annotation_made_at_the_base_survives_the_robot_closing_the_segment(tmp_path, media_root):
    from events.models import Segment
    from events.services import segments

    robot = fresh_site(tmp_path / "robot")
    robot.python(
        "from tests.support.field_day import field_day; field_day(close=False)\n"
        "from events.models import Segment\n"
        "from events.services import segments\n"
        "master = Segment.objects.get(parent=None, end=None)\n"
        "print('SECOND', segments.add_ito_child(master).uid)\n"
    )
    robot.manage("ftt_export", str(tmp_path / "first.zip"))
    load(tmp_path / "first.zip")
    # The operator at the base station gives the robot's open take-over its reason ...
    second = Segment.objects.get(parent__isnull=False, end=None, ito_reason="unassigned")
    segments.annotate_segment(second, ito_reason="planner", obstacle="ditch")
    # ... and later the robot, still offline, drives on: the take-over ends there.
    robot.python(
        "from events.models import Segment\n"
        "from events.services import segments\n"
        "segments.close_segment(Segment.objects.get(parent=None, end=None))\n"
    )
    robot.manage("ftt_export", str(tmp_path / "second.zip"))
    plan = load(tmp_path / "second.zip")
    assert plan.counts["segments"]["updated"] >= 2  # the master and its reasons ended
    second.refresh_from_db()
    assert (second.ito_reason_id, second.obstacle) == ("planner", "ditch")
    assert second.end is not None and second.parent.end is not None
    # The robot's own annotation of the first reason came across as well.
    first = second.parent.children.exclude(pk=second.pk).get()
    assert (first.ito_reason_id, first.obstacle) == ("safety", "fence")
