"""On the embedded database a process reads SpatiaLite and renders tiles with
rasterio; both bring GDAL/PROJ libraries, and the wrong load order crashed the
process (segfault) the first time a tile was drawn after a database read."""

import os
import subprocess
import sys
from pathlib import Path

from tests.support.sites import copy_migrated_database

ROOT = Path(__file__).resolve().parents[2]

READ_THEN_TILE = """
import django
django.setup()
from events.models import Vehicle
print("vehicles", Vehicle.objects.count(), flush=True)
from basemaps.selectors import tiles
print("tiles module", tiles.__name__)
"""


def test_a_tile_module_loads_after_a_spatialite_read(tmp_path):
    env = {k: v for k, v in os.environ.items() if not k.startswith("FTT_")}
    env.update(
        DJANGO_SETTINGS_MODULE="ftt_site.settings",
        FTT_DATA_DIR=str(tmp_path),
        PYTHONPATH=str(ROOT),
    )
    copy_migrated_database(tmp_path)
    run = subprocess.run(
        [sys.executable, "-c", READ_THEN_TILE],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, f"exit {run.returncode}: {run.stderr[-2000:]}"
    assert "vehicles 0" in run.stdout and "tiles module basemaps.selectors.tiles" in run.stdout
