"""`manage.py check --deploy` under the production environment of the README.

The check runs in a subprocess because settings are read once, from the
environment, when Django starts.
"""

import os
import secrets
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

PRODUCTION = {
    "FTT_DEBUG": "0",
    "FTT_HTTPS": "1",
    "FTT_SECRET_KEY": secrets.token_urlsafe(48),  # 64 characters
    "FTT_ALLOWED_HOSTS": "ftt.example.org",
    "FTT_CSRF_TRUSTED_ORIGINS": "https://ftt.example.org",
}


def deploy_check(tmp_path, **overrides):
    env = {key: value for key, value in os.environ.items() if not key.startswith("FTT_")}
    # Keep the database the suite runs on; the check does not connect to it.
    if "FTT_DATABASE_URL" in os.environ:
        env["FTT_DATABASE_URL"] = os.environ["FTT_DATABASE_URL"]
    env.update(PRODUCTION, FTT_DATA_DIR=str(tmp_path), DJANGO_SETTINGS_MODULE="ftt_site.settings")
    env.update(overrides)
    return subprocess.run(
        [sys.executable, "manage.py", "check", "--deploy", "--fail-level", "WARNING"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_production_settings_pass_the_deploy_check(tmp_path):
    result = deploy_check(tmp_path)
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "System check identified no issues" in output


@pytest.mark.parametrize(
    ("overrides", "warning"),
    [
        ({"FTT_HTTPS": "0"}, "security.W012"),  # session cookie not secure
        ({"FTT_DEBUG": "1"}, "security.W018"),
        ({"FTT_SECRET_KEY": "short"}, "security.W009"),
        ({"FTT_HSTS_SECONDS": "0"}, "security.W004"),
    ],
    ids=["http", "debug", "weak-key", "no-hsts"],
)
def test_insecure_settings_fail_the_deploy_check(tmp_path, overrides, warning):
    result = deploy_check(tmp_path, **overrides)
    output = result.stdout + result.stderr
    assert result.returncode != 0, output
    assert warning in output
