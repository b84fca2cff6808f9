"""Whole-installation backup for administrators: the database and every media file.

The result is a zip with a manifest (format ``ftt-backup``) holding
``database/database.pgdump`` (pg_dump custom format) on PostGIS or
``database/ftt.sqlite3`` (a consistent copy made with SQLite's online backup)
on SpatiaLite, and ``media/...``.  docs/data-exchange.md gives the restore steps.
"""

import os
import re
import shutil
import sqlite3  # the build Django uses: settings (ftt_site.sqlite_shim) choose it before apps load
import subprocess
import tempfile
from pathlib import Path

from django.conf import settings
from django.db import connection

from exchange.archive import ArchiveWriter

BACKUP_FORMAT = "ftt-backup"


class BackupError(Exception):
    pass


def pg_tool(name: str, server_major: int) -> str:
    """A client tool at least as new as the server; pg_dump refuses older servers' peers."""
    candidates = [f"/usr/lib/postgresql/{server_major}/bin/{name}", shutil.which(name)]
    found = []
    for path in filter(None, candidates):
        if not os.access(path, os.X_OK):
            continue
        out = subprocess.run([path, "--version"], capture_output=True, text=True).stdout
        match = re.search(r"(\d+)(?:\.\d+)?", out)
        major = int(match.group(1)) if match else 0
        found.append(f"{path} ({major})")
        if major >= server_major:
            return path
    raise BackupError(
        f"No {name} for PostgreSQL {server_major} or newer (found: {', '.join(found) or 'none'});"
        f" install postgresql-client-{server_major}."
    )


def _dump_postgres(target: Path) -> Path:
    db = connection.settings_dict
    connection.ensure_connection()
    major = connection.pg_version // 10000
    out = target / "database.pgdump"
    command = [
        pg_tool("pg_dump", major),
        "--format=custom",
        "--no-owner",
        "--no-privileges",
        "--dbname",
        db["NAME"],
        "--file",
        str(out),
    ]
    for flag, key in (("--host", "HOST"), ("--port", "PORT"), ("--username", "USER")):
        if db.get(key):
            command += [flag, str(db[key])]
    env = os.environ | ({"PGPASSWORD": db["PASSWORD"]} if db.get("PASSWORD") else {})
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise BackupError(f"pg_dump failed: {done.stderr.strip()[-1000:]}")
    return out


def _copy_sqlite(target: Path) -> Path:
    out = target / "ftt.sqlite3"
    source = sqlite3.connect(f"file:{connection.settings_dict['NAME']}?mode=ro", uri=True)
    copy = sqlite3.connect(out)
    try:
        # The online backup copies one consistent state even while the collector writes.
        source.backup(copy)
        copy.execute("PRAGMA journal_mode=DELETE")  # one self-contained file, no -wal
    finally:
        copy.close()
        source.close()
    return out


def make_backup(path) -> dict:
    media = Path(settings.MEDIA_ROOT)
    with tempfile.TemporaryDirectory(prefix="ftt-backup-") as scratch:
        scratch = Path(scratch)
        if connection.vendor == "postgresql":
            dump = _dump_postgres(scratch)
        elif connection.vendor == "sqlite":
            dump = _copy_sqlite(scratch)
        else:  # pragma: no cover - settings allow only these two
            raise BackupError(f"No backup method for {connection.vendor}.")
        selection = {"database": connection.vendor, "media_root": str(media)}
        with ArchiveWriter(path, selection=selection, format=BACKUP_FORMAT) as out:
            with open(dump, "rb") as handle:
                out.write_member(f"database/{dump.name}", handle)
            files = 0
            if media.is_dir():
                for file in sorted(p for p in media.rglob("*") if p.is_file()):
                    with open(file, "rb") as handle:
                        out.write_member(f"media/{file.relative_to(media).as_posix()}", handle)
                    files += 1
            out.counts = {"media_files": files}
        return out.manifest
