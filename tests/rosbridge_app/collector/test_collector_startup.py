"""What ``manage.py ftt_collect`` has loaded when it subscribes to its first topic.

Every library loaded before that is start-up time with nothing recorded (a
restart after a crash on a robot). The collector needs Django, its models, the
ROS messages and its own pipeline; the web's report, raster and API stacks
and the directory client are for other processes. Asserted on the modules, not
on seconds, so that a loaded machine cannot make it pass or fail.
"""

import json
import os
import subprocess
import sys

import pytest

from tests.support.ros import ROOT, requires_ros

pytestmark = [pytest.mark.ros, requires_ros]

# Libraries the collector never uses (some of them seconds to load).
NOT_FOR_THE_COLLECTOR = (
    "matplotlib",  # the report's figures
    "typst",  # the report's typesetting
    "scipy",
    "rasterio",  # basemap tiles
    "rio_tiler",
    "cv2",  # only for compressed camera images, loaded with the first one
    "rest_framework.serializers",  # the API
    "requests",
    "ldap",  # directory sign-in
    "ftt_site.urls",
    "rosbridge_app.collector.mode_presets",  # for the command and the GUI's editor
)

# Runs manage.py ftt_collect; at its first subscription it writes the loaded
# modules to the file named by argv[1] and ends the process.
AT_FIRST_SUBSCRIPTION = """
import json, os, runpy, sys
import rclpy.node

out = sys.argv[1]

def first_subscription(self, *args, **kwargs):
    with open(out, "w") as f:
        json.dump(sorted(sys.modules), f)
    os._exit(0)

rclpy.node.Node.create_subscription = first_subscription
sys.argv = ["manage.py", "ftt_collect", *sys.argv[2:]]
runpy.run_path("manage.py", run_name="__main__")
"""


@pytest.mark.parametrize("database", ["postgis", "spatialite"])
def test_the_collector_subscribes_without_the_web_stacks(database, tmp_path):
    env = {
        **os.environ,
        "DJANGO_SETTINGS_MODULE": "ftt_site.settings",
        "FTT_DATA_DIR": str(tmp_path / "data"),
    }
    if database == "postgis":
        if not os.environ.get("FTT_DATABASE_URL", "").startswith(("postgis:", "postgres")):
            pytest.skip("FTT_DATABASE_URL names no PostgreSQL database")
    else:
        env.pop("FTT_DATABASE_URL", None)
    out = tmp_path / "modules.json"
    run = subprocess.run(
        [
            sys.executable,
            "-c",
            AT_FIRST_SUBSCRIPTION,
            str(out),
            "--spool",
            str(tmp_path / "spool.sqlite3"),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and out.exists(), run.stdout + run.stderr
    loaded = set(json.loads(out.read_text()))
    # It did get as far as its own node (the check below is not vacuous).
    assert {"rosbridge_app.collector.node", "telemetry.models"} <= loaded
    assert [name for name in NOT_FOR_THE_COLLECTOR if name in loaded] == []
