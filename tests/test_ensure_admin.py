"""manage.py ftt_ensure_admin, which scripts/run.sh calls on every start (through ftt_prepare)."""

import stat
from io import StringIO

import pytest
from django.contrib.auth.models import User
from django.core.management import call_command

from common.roles import ADMINISTRATOR

pytestmark = pytest.mark.django_db


@pytest.fixture
def data_dir(settings, tmp_path, monkeypatch):
    for name in ("FTT_ADMIN_USER", "FTT_ADMIN_PASSWORD", "FTT_ADMIN_EMAIL"):
        monkeypatch.delenv(name, raising=False)
    settings.DATA_DIR = tmp_path
    return tmp_path


def ensure_admin() -> str:
    out = StringIO()
    call_command("ftt_ensure_admin", stdout=out)
    return out.getvalue()


def test_creates_an_administrator_with_a_generated_password(data_dir):
    output = ensure_admin()

    user = User.objects.get(username="admin")
    password = (data_dir / "admin_password.txt").read_text().strip()
    assert password in output
    assert user.check_password(password)
    assert user.is_superuser and user.is_staff and user.is_active
    assert user.groups.filter(name=ADMINISTRATOR).exists()
    assert stat.S_IMODE((data_dir / "admin_password.txt").stat().st_mode) == 0o600


def test_second_run_keeps_the_account_and_does_not_print_the_password(data_dir):
    ensure_admin()
    password = (data_dir / "admin_password.txt").read_text().strip()

    output = ensure_admin()

    assert password not in output
    assert "admin_password.txt" in output
    assert User.objects.filter(username="admin").count() == 1
    assert User.objects.get(username="admin").check_password(password)


def test_credentials_from_the_environment(data_dir, monkeypatch):
    monkeypatch.setenv("FTT_ADMIN_USER", "chief")
    monkeypatch.setenv("FTT_ADMIN_PASSWORD", "Correct-Horse-7")
    monkeypatch.setenv("FTT_ADMIN_EMAIL", "chief@example.org")

    output = ensure_admin()

    user = User.objects.get(username="chief")
    assert user.check_password("Correct-Horse-7")
    assert user.email == "chief@example.org"
    assert "Correct-Horse-7" not in output
    assert not (data_dir / "admin_password.txt").exists()


def test_password_from_the_environment_replaces_a_generated_one(data_dir, monkeypatch):
    ensure_admin()
    monkeypatch.setenv("FTT_ADMIN_PASSWORD", "Another-Secret-9")

    ensure_admin()

    assert User.objects.get(username="admin").check_password("Another-Secret-9")
    assert not (data_dir / "admin_password.txt").exists()


def test_repairs_an_existing_account_without_rights(data_dir, monkeypatch):
    User.objects.create_user("admin", password="Old-Password-1", is_active=False)

    ensure_admin()

    user = User.objects.get(username="admin")
    assert user.is_superuser and user.is_staff and user.is_active
    assert user.groups.filter(name=ADMINISTRATOR).exists()
    assert user.check_password("Old-Password-1")
    assert not (data_dir / "admin_password.txt").exists()
