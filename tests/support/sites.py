"""Run manage.py for another installation (its own SpatiaLite file and media) in a child process."""

import hashlib
import json
import os
import sqlite3
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# FTT's apps, whose code a migration can run (the tests' is not among it).
APPS = sorted(path.parent.name for path in ROOT.glob("*/apps.py"))


def code_digest() -> str:
    """Names a migrated database by the code that made it."""
    digest = hashlib.sha256(sys.version.encode())
    for path in sorted(p for app in APPS for p in (ROOT / app).rglob("*.py")):
        digest.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def copy_migrated_database(data_dir: Path) -> None:
    """Puts a fully migrated embedded database into ``data_dir`` (which has none),
    as ``manage.py migrate`` would make it: migrated once per version of the code
    and copied, instead of replaying the whole chain of migrations per site."""
    data_dir.mkdir(parents=True, exist_ok=True)
    copy_sqlite(migrated_template(), data_dir / "ftt.sqlite3")


def migrated_template() -> Path:
    """The embedded database ``manage.py migrate`` makes from this code, made once."""
    template = Path(tempfile.gettempdir()) / "ftt-test-migrated" / f"{code_digest()}.sqlite3"
    if not template.exists():
        build = Path(tempfile.mkdtemp(prefix="ftt-migrating-"))
        Site(build).manage("migrate", "--noinput", "-v", "0")
        template.parent.mkdir(exist_ok=True)
        part = template.with_suffix(f".{os.getpid()}.part")
        copy_sqlite(build / "ftt.sqlite3", part)
        part.replace(template)  # atomic: another worker may be making the same
    return template


def copy_sqlite(source: Path, target: Path) -> None:
    # SQLite's backup copies a consistent state, WAL or not; a WAL left by an
    # earlier database of that name would be replayed into the copy.
    for leftover in ("-wal", "-shm"):
        target.with_name(target.name + leftover).unlink(missing_ok=True)
    with sqlite3.connect(source) as src, sqlite3.connect(target) as dst:
        src.backup(dst)
    target.chmod(0o600)


class Site:
    def __init__(self, data_dir: Path, root: Path = ROOT, **env: str):
        """``env`` adds FTT_* variables, e.g. FTT_DATABASE_URL for a PostGIS site;
        ``root`` is the code that runs it (another tree: an older FTT)."""
        self.data_dir = Path(data_dir)
        self.root = Path(root)
        self.env = {k: v for k, v in os.environ.items() if k != "FTT_DATABASE_URL"}
        self.env |= {"FTT_DATA_DIR": str(self.data_dir), "FTT_LOG_LEVEL": "WARNING"}
        self.env.pop("FTT_MEDIA_ROOT", None)
        self.env |= env

    def manage(self, *args: str) -> str:
        done = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=self.root,
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
    copy_migrated_database(data_dir)
    return Site(data_dir)
