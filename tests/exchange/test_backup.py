"""Whole-database backup, restored the way docs/data-exchange.md tells administrators."""

import json
import os
import subprocess
import zipfile

import pytest
from django.core.management import call_command
from django.db import connection
from rest_framework.authtoken.models import Token

from common import roles
from exchange.backup import make_backup
from tests.support.field_day import field_day
from tests.support.sites import Site
from tests.support.snapshot import snapshot

# The backup reads the database from outside this test's connection, so the
# data must be committed.
# On SpatiaLite too: a backup copies the SQLite file or dumps PostgreSQL.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db(transaction=True)]


def unpack(backup, target):
    with zipfile.ZipFile(backup) as z:
        manifest = json.loads(z.read("manifest.json"))
        assert manifest["format"] == "ftt-backup"
        z.extractall(target)
    return manifest


@pytest.mark.skipif(connection.vendor != "sqlite", reason="SpatiaLite backup")
def test_spatialite_backup_restores_to_an_equal_installation(tmp_path, media_root):
    field_day()
    before = json.loads(json.dumps(snapshot()))
    call_command("ftt_backup", str(tmp_path / "backup.zip"), stdout=open(os.devnull, "w"))
    manifest = unpack(tmp_path / "backup.zip", tmp_path / "unpacked")
    assert manifest["counts"]["media_files"] == 2
    restored = tmp_path / "restored"
    restored.mkdir()
    (tmp_path / "unpacked/database/ftt.sqlite3").rename(restored / "ftt.sqlite3")
    (tmp_path / "unpacked/media").rename(restored / "media")
    assert Site(restored).snapshot() == before


def test_an_administrators_backup_holds_no_session_token_or_password_hash(
    tmp_path, media_root, api_client, client, django_user_model
):
    owner = django_user_model.objects.create_superuser("owner", password="a long passphrase")
    client.force_login(owner)
    session_key = client.cookies["sessionid"].value
    robot_token = Token.objects.create(user=django_user_model.objects.create_user("r2"))
    administrator = api_client(roles.ADMINISTRATOR)
    secrets = [session_key, robot_token.key, administrator.user.auth_token.key, owner.password]
    response = administrator.get("/api/backup/")
    assert response.status_code == 200
    (tmp_path / "backup.zip").write_bytes(b"".join(response.streaming_content))
    with zipfile.ZipFile(tmp_path / "backup.zip") as z:
        contents = b"".join(z.read(name) for name in z.namelist())
        assert json.loads(z.read("manifest.json"))["selection"]["credentials"] is False
    assert not [secret for secret in secrets if secret.encode() in contents]
    # The owner's full copy keeps them.
    call_command(
        "ftt_backup", str(tmp_path / "full.zip"), "--with-credentials", stdout=open(os.devnull, "w")
    )
    with zipfile.ZipFile(tmp_path / "full.zip") as z:
        assert json.loads(z.read("manifest.json"))["selection"]["credentials"] is True


@pytest.mark.postgis_only
@pytest.mark.skipif(connection.vendor != "postgresql", reason="PostGIS backup")
@pytest.mark.parametrize("credentials", [True, False], ids=["pg_restore", "psql"])
def test_postgis_backup_restores_as_the_doc_says(tmp_path, media_root, credentials):
    field_day()
    before = json.loads(json.dumps(snapshot()))
    make_backup(tmp_path / "backup.zip", credentials=credentials)
    unpack(tmp_path / "backup.zip", tmp_path / "unpacked")
    db = connection.settings_dict
    target = f"{db['NAME']}_restored"
    env = os.environ | {"PGPASSWORD": db["PASSWORD"]}
    server = ["-h", db["HOST"], "-p", str(db["PORT"] or 5432), "-U", db["USER"]]
    subprocess.run(["dropdb", "--if-exists", "--force", *server, target], env=env, check=True)
    subprocess.run(["createdb", *server, target], env=env, check=True)
    try:
        if credentials:
            restore = [
                "pg_restore",
                "--no-owner",
                "--exit-on-error",
                *server,
                "-d",
                target,
                str(tmp_path / "unpacked/database/database.pgdump"),
            ]
        else:
            restore = [
                "psql",
                "--quiet",
                "-v",
                "ON_ERROR_STOP=1",
                *server,
                "-d",
                target,
                "-f",
                str(tmp_path / "unpacked/database/database.sql"),
            ]
        subprocess.run(restore, env=env, check=True, capture_output=True)  # fmt: skip
        url = f"postgis://{db['USER']}:{db['PASSWORD']}@{db['HOST']}:{db['PORT'] or 5432}/{target}"
        site = Site(
            tmp_path / "site",
            FTT_DATABASE_URL=url,
            FTT_MEDIA_ROOT=str(tmp_path / "unpacked/media"),
        )
        assert site.snapshot() == before
    finally:
        subprocess.run(["dropdb", "--if-exists", "--force", *server, target], env=env)
