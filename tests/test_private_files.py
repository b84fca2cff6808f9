"""The database, the secret key and the data directory are FTT's user's only,
from the moment they exist, whatever the umask of whoever starts FTT."""

import os
import stat
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_database_secret_key_and_data_directory_are_private(tmp_path):
    data = tmp_path / "data"
    env = {k: v for k, v in os.environ.items() if not k.startswith("FTT_")}
    env.update(FTT_DATA_DIR=str(data), DJANGO_SETTINGS_MODULE="ftt_site.settings")
    script = (
        "import os; os.umask(0o022); import django; django.setup(); "
        "from django.db import connection; connection.ensure_connection()"
    )
    subprocess.run([sys.executable, "-c", script], cwd=ROOT, env=env, check=True, timeout=120)

    def mode(path):
        return stat.S_IMODE(path.stat().st_mode)

    assert mode(data) == 0o700
    assert mode(data / "secret_key") == 0o600 and (data / "secret_key").read_text().strip()
    assert mode(data / "ftt.sqlite3") == 0o600
