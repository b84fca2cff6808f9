"""Whole-installation backup: the database and every media file.

The result is a zip with a manifest (format ``ftt-backup``) holding the
database and ``media/...``.  docs/data-exchange.md gives the restore steps.

What signs someone in stays out unless ``credentials`` asks for it (only the
machine's owner, through ``manage.py ftt_backup --with-credentials``): sessions,
API tokens and the login-failure records are left out, and every account's
password is replaced by an unusable one, so nobody who holds the backup can sign
in as anyone.  On PostGIS such a backup is a plain SQL dump
(``database/database.sql``) whose ``auth_user`` rows are rewritten as they
stream; with credentials it is ``database/database.pgdump`` (pg_dump custom
format).  On SpatiaLite it is ``database/ftt.sqlite3`` (a consistent copy made
with SQLite's online backup), cleaned and vacuumed so no deleted row lingers in
its free pages.
"""

import os
import re
import shutil
import sqlite3  # the build Django uses: settings (db_spatialite.sqlite_shim) choose it first
import subprocess
import tempfile
from pathlib import Path

from django.apps import apps
from django.conf import settings
from django.contrib.auth import get_user_model
from django.contrib.auth.hashers import make_password
from django.db import connection
from django.utils.translation import gettext as _

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
        _(
            "No %(tool)s for PostgreSQL %(major)s or newer (found: %(found)s); install "
            "postgresql-client-%(major)s."
        )
        % {"tool": name, "major": server_major, "found": ", ".join(found) or _("none")}
    )


# Models whose rows sign someone in (or record who tried to).
CREDENTIAL_MODELS = (
    "sessions.Session",
    "authtoken.Token",
    "axes.AccessAttempt",
    "axes.AccessLog",
    "axes.AccessFailureLog",
)


def credential_tables() -> list[str]:
    return [apps.get_model(label)._meta.db_table for label in CREDENTIAL_MODELS]


def _pg_dump(target: Path, credentials: bool) -> tuple[list[str], dict, Path]:
    db = connection.settings_dict
    connection.ensure_connection()
    major = connection.pg_version // 10000
    out = target / ("database.pgdump" if credentials else "database.sql")
    command = [pg_tool("pg_dump", major), "--no-owner", "--no-privileges", "--dbname", db["NAME"]]
    if credentials:
        command += ["--format=custom", "--file", str(out)]
    else:
        command += ["--format=plain"]
        command += [f"--exclude-table-data={table}" for table in credential_tables()]
    for flag, key in (("--host", "HOST"), ("--port", "PORT"), ("--username", "USER")):
        if db.get(key):
            command += [flag, str(db[key])]
    env = os.environ | ({"PGPASSWORD": db["PASSWORD"]} if db.get("PASSWORD") else {})
    return command, env, out


def _dump_postgres(target: Path, credentials: bool) -> Path:
    command, env, out = _pg_dump(target, credentials)
    if credentials:
        done = subprocess.run(command, env=env, capture_output=True, text=True)
        failed, error = done.returncode != 0, done.stderr
    else:
        with (
            open(out, "w") as sql,
            subprocess.Popen(
                command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
            ) as dump,
        ):
            _write_without_passwords(dump.stdout, sql)
            error = dump.stderr.read()
        failed = dump.returncode != 0
    if failed:
        raise BackupError(_("pg_dump failed: %(error)s") % {"error": error.strip()[-1000:]})
    return out


def _write_without_passwords(lines, out) -> None:
    """Copy a plain pg_dump, with every password in the user table's COPY block
    replaced by an unusable one."""
    header = f"COPY public.{get_user_model()._meta.db_table} ("
    unusable = make_password(None)
    column = None
    for line in lines:
        if column is not None:
            if line.startswith("\\."):
                column = None
            else:
                fields = line.rstrip("\n").split("\t")
                fields[column] = unusable
                line = "\t".join(fields) + "\n"
        elif line.startswith(header):
            names = line[len(header) : line.index(")")].split(", ")
            column = names.index("password")
        out.write(line)


def _remove_credentials(database) -> None:
    database.execute("PRAGMA secure_delete=ON")
    for table in credential_tables():
        database.execute(f'DELETE FROM "{table}"')
    user_table = get_user_model()._meta.db_table
    database.execute(f'UPDATE "{user_table}" SET password = ?', (make_password(None),))
    database.commit()
    database.execute("VACUUM")


def _copy_sqlite(target: Path, credentials: bool) -> Path:
    out = target / "ftt.sqlite3"
    source = sqlite3.connect(f"file:{connection.settings_dict['NAME']}?mode=ro", uri=True)
    copy = sqlite3.connect(out)
    try:
        # The online backup copies one consistent state even while the collector writes.
        source.backup(copy)
        copy.execute("PRAGMA journal_mode=DELETE")  # one self-contained file, no -wal
        if not credentials:
            _remove_credentials(copy)
    finally:
        copy.close()
        source.close()
    return out


def make_backup(path, *, credentials: bool = False) -> dict:
    media = Path(settings.MEDIA_ROOT)
    with tempfile.TemporaryDirectory(prefix="ftt-backup-") as scratch:
        scratch = Path(scratch)
        if connection.vendor == "postgresql":
            dump = _dump_postgres(scratch, credentials)
        elif connection.vendor == "sqlite":
            dump = _copy_sqlite(scratch, credentials)
        else:  # pragma: no cover - settings allow only these two
            raise BackupError(_("No backup method for %(vendor)s.") % {"vendor": connection.vendor})
        selection = {
            "database": connection.vendor,
            "media_root": str(media),
            "credentials": credentials,
        }
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
