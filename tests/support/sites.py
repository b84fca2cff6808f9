"""Run manage.py for another installation (its own SpatiaLite file and media) in a child process."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


class Site:
    def __init__(self, data_dir: Path, **env: str):
        """``env`` adds FTT_* variables, e.g. FTT_DATABASE_URL for a PostGIS site."""
        self.data_dir = Path(data_dir)
        self.env = {k: v for k, v in os.environ.items() if k != "FTT_DATABASE_URL"}
        self.env |= {"FTT_DATA_DIR": str(self.data_dir), "FTT_LOG_LEVEL": "WARNING"}
        self.env.pop("FTT_MEDIA_ROOT", None)
        self.env |= env

    def manage(self, *args: str) -> str:
        done = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=ROOT,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        if done.returncode != 0:
            raise AssertionError(f"manage.py {' '.join(args)} failed:\n{done.stderr[-3000:]}")
        return done.stdout

    def python(self, code: str) -> str:
        return self.manage("shell", "-c", code)

    def snapshot(self, names: bool = False) -> dict:
        out = self.python(
            "import json; from tests.support.snapshot import snapshot; "
            f"print('SNAPSHOT' + json.dumps(snapshot(names={names})))"
        )
        return json.loads(out.split("SNAPSHOT", 1)[1])


def fresh_site(data_dir: Path) -> Site:
    site = Site(data_dir)
    site.manage("migrate", "--noinput", "-v", "0")
    return site
