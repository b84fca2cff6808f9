"""A database made and filled by older FTT migrates with this tree's migrations and
keeps every row, readable through this tree's models (issue 43: existing
databases migrate).  The older code is that of the last commit before the rooms
of issue 43 moved the live layer out of rosbridge_app and modules between apps."""

import json
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

from tests.support.databases import drop_database, older_database
from tests.support.sites import ROOT, Site

pytestmark = pytest.mark.postgis_only

OLDER = "91703aa"

# Run by the older code: a test event > shift > leg > segments with poses, notes
# and an image (the scenario of tests/support), the feed rows its services
# announce, a collector of a robot with a command, an archive import.
FILL = """
from datetime import timedelta
from django.utils import timezone
from events.models import Performer, Vehicle
from exchange.models import ArchiveImport
from rosbridge_app.models import Collector, CollectorCommand
from tests.support.scenario import build_scenario
husky = Vehicle.objects.create(key="husky", short_description="Husky A200", institution="FKIE")
jackal = Vehicle.objects.create(key="jackal", short_description="Jackal", institution="FKIE")
scenario = build_scenario(husky, jackal, Performer.objects.create(institution="Fraunhofer FKIE"))
leg = scenario.shifts[0].legs.get()
collector = Collector.objects.create(
    name="husky-collector", vehicle=husky, host="husky", pid=4242, logging=True, leg=leg,
    stored=17, hearing="ok", topics=["/gps/fix"], inputs={"/gps/fix": 0.4},
    stopped=timezone.now() + timedelta(minutes=1),
)
CollectorCommand.objects.create(collector=collector, kind="snapshot", arguments={"seconds": 30})
ArchiveImport.objects.create(filename="campaign.ftt", counts={"segments": 9}, lines=["9 segments"])
"""

# Run by either code: every row of every FTT model as its ORM reads it, by table.
DUMP = """
import json
from django.apps import apps
FTT = {"common", "events", "telemetry", "rosbridge_app", "exchange", "reports", "basemaps", "live"}
rows = {}
for model in apps.get_models():
    if model._meta.app_label in FTT and model._meta.managed:
        rows[model._meta.db_table] = {
            str(row["pk"]): row
            for row in model.objects.values("pk", *(f.attname for f in model._meta.concrete_fields))
        }
print("ROWS" + json.dumps(rows, default=str, sort_keys=True))
"""


def _rows(site: Site) -> dict:
    return json.loads(site.python(DUMP).split("ROWS", 1)[1])


@pytest.fixture
def older_tree():
    tree = Path(tempfile.mkdtemp(prefix="ftt-older-"))
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", OLDER], capture_output=True, check=False
    )
    assert archive.returncode == 0, (
        f"commit {OLDER} is missing: the test needs the repository's history "
        f"(a full clone): {archive.stderr.decode()}"
    )
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
    yield tree
    shutil.rmtree(tree, ignore_errors=True)


def test_a_database_of_older_ftt_keeps_every_row_after_this_trees_migrations(older_tree, tmp_path):
    url = older_database(older_tree, OLDER)
    try:
        older = Site(tmp_path, root=older_tree, FTT_DATABASE_URL=url)
        older.python(FILL)
        before = _rows(older)
        assert before["telemetry_pose"] and before["rosbridge_app_announcement"]
        assert before["rosbridge_app_collector"] and before["exchange_archiveimport"]

        now = Site(tmp_path, FTT_DATABASE_URL=url)
        now.manage("migrate", "--noinput", "-v", "0")
        after = _rows(now)
    finally:
        drop_database(url)

    # Every table the older code wrote holds the same rows with the same values
    # (columns added since may hold more).
    assert sorted(before) == sorted(t for t in before if t in after)
    for table, rows in before.items():
        assert sorted(after[table]) == sorted(rows), table
        for pk, row in rows.items():
            assert {k: after[table][pk][k] for k in row} == row, (table, pk)
