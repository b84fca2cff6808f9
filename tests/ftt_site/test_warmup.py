"""A web process loads its views before it takes a request (ftt_site.server.warmup), so
the first visitor after a restart does not wait for the imports (about 1.3 s)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

# On SpatiaLite too: a worker's warm-up opens the embedded database its own way.
pytestmark = pytest.mark.spatialite

ROOT = Path(__file__).resolve().parents[2]

PROBE = """
import json, sys
import ftt_site.asgi
print(json.dumps({
    "urls_loaded": all(
        name in sys.modules for name in ("ftt_site.urls", "ftt_site.api_urls", "gui.urls")
    ),
    "report_charts_imported": "matplotlib" in sys.modules,
}))
"""


def test_the_asgi_application_has_its_views_loaded_before_the_first_request():
    env = {**os.environ, "DJANGO_SETTINGS_MODULE": "ftt_site.settings"}
    done = subprocess.run(
        [sys.executable, "-c", PROBE],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    state = json.loads(done.stdout.strip().splitlines()[-1])
    assert state == {"urls_loaded": True, "report_charts_imported": True}
