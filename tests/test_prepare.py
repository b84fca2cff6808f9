"""manage.py ftt_prepare, scripts/run.sh's one step before serving: a restart
with nothing changed runs neither the system checks nor the migrations."""

from io import StringIO
from unittest import mock

import pytest
from django.core.management import call_command

from ftt_site.management.commands import ftt_prepare

pytestmark = pytest.mark.django_db


@pytest.fixture
def data_dir(settings, tmp_path, monkeypatch):
    monkeypatch.setenv("FTT_ADMIN_PASSWORD", "prepare-pw-1")
    settings.DATA_DIR = tmp_path
    return tmp_path


def prepare(*args) -> tuple[str, list[str]]:
    """The command's output, and what it ran: "checks", "migrate"."""
    ran = []
    real_check = ftt_prepare.Command.check
    real_call = ftt_prepare.call_command

    def check(self, *a, **k):
        ran.append("checks")
        return real_check(self, *a, **k)

    def call(name, *a, **k):
        ran.append(name)
        return real_call(name, *a, **k)

    out = StringIO()
    with (
        mock.patch.object(ftt_prepare.Command, "check", check),
        mock.patch.object(ftt_prepare, "call_command", call),
    ):
        call_command("ftt_prepare", *args, stdout=out)
    return out.getvalue(), ran


def test_a_restart_with_nothing_changed_skips_checks_and_migrations(data_dir):
    _, first = prepare()
    assert first == ["checks", "ftt_ensure_admin"]  # the test database is migrated
    output, again = prepare()
    assert again == ["ftt_ensure_admin"]
    assert "nothing changed since they last passed" in output
    assert "all applied" in output


def test_changed_settings_or_code_run_the_checks_again(data_dir, monkeypatch):
    prepare()
    monkeypatch.setenv("FTT_HTTPS", "1")
    assert prepare()[1] == ["checks", "ftt_ensure_admin"]
    assert prepare()[1] == ["ftt_ensure_admin"]
    monkeypatch.setattr(ftt_prepare, "checked_digest", lambda: "other code")
    assert prepare()[1] == ["checks", "ftt_ensure_admin"]
    assert prepare("--check")[1] == ["checks", "ftt_ensure_admin"]


def test_a_missing_migration_is_applied(data_dir, monkeypatch):
    monkeypatch.setattr(ftt_prepare, "missing_migrations", lambda: ["events.9999_new"])
    with mock.patch.object(ftt_prepare, "call_command") as called:
        call_command("ftt_prepare", stdout=StringIO())
    assert [c.args[0] for c in called.call_args_list] == ["migrate", "ftt_ensure_admin"]
