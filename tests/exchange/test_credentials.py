"""Restoring a backup without credentials keeps the target's accounts signing in."""

import json
import shutil
import stat
import subprocess
import sys
import zipfile

from tests.support.sites import ROOT, Site, fresh_site

ACCOUNTS = """
from django.contrib.auth.models import Group, User
from events.models import Vehicle
from events.services.robots import ensure_robot_account
alice = User.objects.create_user("alice", password="alice-pw-1")
alice.groups.add(Group.objects.get(name="operator"))
vehicle = Vehicle.objects.create(key="husky", short_description="Husky")
print("TOKEN" + ensure_robot_account("husky-robot", [vehicle]).token)
"""

SIGN_INS = """
import json
from django.contrib.auth.models import User
from common.api.authentication import token_account
from common import roles
user = User.objects.filter(username="alice").first()
user = user if user is not None and user.check_password("alice-pw-1") else None
try:
    robot = token_account({token!r})[0]
except Exception:
    robot = None
print("SIGNINS" + json.dumps({{
    "alice": user is not None and roles.has_role(user, "operator"),
    "robot": robot is not None and roles.is_robot(robot),
}}))
"""


def sign_ins(site: Site, token: str) -> dict:
    out = site.python(SIGN_INS.format(token=token))
    return json.loads(out.split("SIGNINS", 1)[1])


def test_saved_sign_ins_come_back_after_a_restore(tmp_path):
    site = fresh_site(tmp_path / "site")
    token = site.python(ACCOUNTS).split("TOKEN", 1)[1].strip()
    assert sign_ins(site, token) == {"alice": True, "robot": True}

    site.manage("ftt_backup", str(tmp_path / "backup.zip"))
    saved = tmp_path / "sign-ins.json"
    assert "2 account(s)" in site.manage("ftt_credentials", "save", str(saved))
    assert stat.S_IMODE(saved.stat().st_mode) == 0o600

    # The restore of docs/data-exchange.md, SpatiaLite.
    with zipfile.ZipFile(tmp_path / "backup.zip") as backup:
        backup.extract("database/ftt.sqlite3", tmp_path / "restore")
    for suffix in ("-wal", "-shm"):
        (site.data_dir / f"ftt.sqlite3{suffix}").unlink(missing_ok=True)
    shutil.copy(tmp_path / "restore/database/ftt.sqlite3", site.data_dir / "ftt.sqlite3")
    assert sign_ins(site, token) == {"alice": False, "robot": False}

    out = site.manage("ftt_credentials", "restore", str(saved))
    assert "2 account(s) kept, 0 made again" in out
    assert sign_ins(site, token) == {"alice": True, "robot": True}


def test_a_file_that_is_not_saved_sign_ins_is_refused(tmp_path):
    site = fresh_site(tmp_path / "site")
    wrong = tmp_path / "wrong.json"
    wrong.write_text('{"format": "something else"}')
    done = subprocess.run(
        [sys.executable, "manage.py", "ftt_credentials", "restore", str(wrong)],
        cwd=ROOT,
        env=site.env,
        capture_output=True,
        text=True,
    )
    assert done.returncode != 0
    assert "is not a file of ftt_credentials save" in done.stderr
