"""The shell machinery: syntax, README ↔ .ci/run, apt alternatives, warm setup."""

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = sorted(
    [*ROOT.glob("scripts/*.sh"), *ROOT.glob("scripts/setup.d/*.sh"), ROOT / ".ci" / "run"]
)


def readme_commands() -> list[str]:
    """The one-line commands in the README's bash code blocks, in order."""
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    return [b.strip() for b in blocks if b.strip().startswith("bash scripts/")]


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_shell_syntax(script):
    result = subprocess.run(["bash", "-n", script], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


def test_readme_has_the_two_commands_and_ci_runs_the_second():
    assert readme_commands() == ["bash scripts/run.sh", "bash scripts/test.sh"]
    ci = ROOT / ".ci" / "run"
    assert os.access(ci, os.X_OK)
    lines = [
        line.strip()
        for line in ci.read_text().splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    assert lines[0] == "set -euo pipefail"
    assert lines[-1] == readme_commands()[1]


def fake_tool(bin_dir: Path, name: str, body: str) -> None:
    path = bin_dir / name
    path.write_text("#!/usr/bin/env bash\n" + body)
    path.chmod(0o755)


def test_apt_alternatives_pick_what_is_installed_or_available(tmp_path):
    """ftt_apt_ensure against fake dpkg/apt: an Ubuntu 24.04-like system."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    log = tmp_path / "apt.log"
    fake_tool(bin_dir, "id", "echo 0\n")
    # Installed: libproj25 only. Offered: the Ubuntu 24.04 names.
    fake_tool(
        bin_dir,
        "dpkg-query",
        'case "${@: -1}" in libproj25) echo "install ok installed";; *) exit 1;; esac\n',
    )
    fake_tool(
        bin_dir,
        "apt-cache",
        'case "$2" in libgdal34t64|libgeos-c1t64|libsqlite3-mod-spatialite)'
        ' echo "  Candidate: 1.0";; *) echo "  Candidate: (none)";; esac\n',
    )
    fake_tool(bin_dir, "apt-get", f'echo "$*" >> {log}\n')
    script = (
        f"source {ROOT}/scripts/lib.sh\n"
        'ftt_apt_ensure "libgdal32|libgdal34t64" "libgeos-c1v5|libgeos-c1t64" '
        '"libproj25" "libsqlite3-mod-spatialite"\n'
        'ftt_apt_ensure "libproj25"\n'
        'ftt_apt_ensure "not-packaged-anywhere" && echo unexpected\n'
    )
    env = {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}"}
    result = subprocess.run(["bash", "-c", script], env=env, capture_output=True, text=True)

    assert result.returncode != 0
    assert "no apt package for: not-packaged-anywhere" in result.stderr
    assert "unexpected" not in result.stdout
    calls = log.read_text().splitlines()
    assert calls[0] == "update -qq"
    assert calls[1].startswith("install ")
    assert calls[1].split()[-3:] == [
        "libgdal34t64",
        "libgeos-c1t64",
        "libsqlite3-mod-spatialite",
    ]
    assert len(calls) == 2  # one update, one install; libproj25 never asked for again


SNAP_STUB = "echo \"Command '$0' requires the chromium snap to be installed.\" >&2; exit 1\n"


def run_with(bin_dir: Path, script: str, **env) -> subprocess.CompletedProcess:
    environment = {**os.environ, **env, "PATH": f"{bin_dir}:{os.environ['PATH']}"}
    return subprocess.run(
        ["bash", "-c", f"source {ROOT}/scripts/lib.sh\n{script}"],
        env=environment,
        capture_output=True,
        text=True,
    )


def test_a_snap_stub_is_not_taken_for_a_browser(tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    fake_tool(bin_dir, "chromium", SNAP_STUB)
    fake_tool(bin_dir, "chromium-browser", 'echo "Chromium 150.0"\n')
    found = run_with(bin_dir, "ftt_working_chromium")
    assert found.returncode == 0 and found.stdout.strip() == str(bin_dir / "chromium-browser")
    fake_tool(bin_dir, "chromium-browser", SNAP_STUB)
    assert run_with(bin_dir, "ftt_working_chromium").returncode == 1


def test_without_a_working_chromium_the_setup_fetches_playwrights_once(tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    venv = tmp_path / "venv"
    venv.mkdir()
    calls = tmp_path / "calls.log"
    for name in ("chromium", "chromium-browser"):
        fake_tool(bin_dir, name, SNAP_STUB)
    fake_tool(
        bin_dir,
        "fake-python",
        f'echo "$*" >> {calls}\n[ "$3" = --version ] && echo "Version 1.65.0"\nexit 0\n',
    )
    hook = f"source {ROOT}/scripts/setup.d/60-test-browser.sh"
    env = {"FTT_SETUP_MODE": "test", "FTT_VENV": str(venv), "FTT_PY": str(bin_dir / "fake-python")}
    first = run_with(bin_dir, hook, **env)
    assert first.returncode == 0, first.stderr
    assert "installing Playwright's Chromium" in first.stderr + first.stdout
    second = run_with(bin_dir, hook, **env)
    assert second.returncode == 0, second.stderr
    installs = [c for c in calls.read_text().splitlines() if "install" in c]
    assert installs == ["-m playwright install --with-deps chromium"]
    # With a working Chromium from apt nothing is fetched at all.
    fake_tool(bin_dir, "chromium", 'echo "Chromium 150.0"\n')
    calls.write_text("")
    assert run_with(bin_dir, hook, **env).returncode == 0
    assert calls.read_text() == ""


@pytest.mark.skipif(
    "FTT_ROOT" not in os.environ, reason="only under scripts/test.sh, which has run setup"
)
def test_second_setup_run_only_checks():
    result = subprocess.run(
        ["bash", "scripts/setup.sh", "--test"], cwd=ROOT, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    # Nothing is installed or built again; the setup only checks.
    assert "apt-get" not in result.stdout
    assert "already installed" in result.stdout


@pytest.mark.parametrize(
    ("folder", "says"),
    [
        ("no_such_msgs", "{tmp}/no_such_msgs does not exist"),
        ("Team-Msgs", "'Team-Msgs' is no ROS package name"),
        ("bad_msgs", "{tmp}/bad_msgs/State.msg: 'strin' is an invalid message name"),
        ("geo_msgs", "State.msg uses geographic_msgs, which is not installed"),
        ("ros1_msgs", "State.msg uses Header, which is no message of {tmp}/ros1_msgs"),
    ],
)
def test_a_wrong_interface_folder_is_named_before_anything_is_built(tmp_path, folder, says):
    """Setup's ROS interface step with FTT_ROS_INTERFACES (relative to where it
    runs) into a temporary prefix: refused at once, saying what is wrong."""
    venv_python = ROOT / ".venv" / "bin" / "python"
    check = subprocess.run([venv_python, "-c", "import rclpy, rosidl_adapter"], capture_output=True)
    if check.returncode != 0:
        pytest.skip("no rclpy and rosidl tools in .venv (scripts/setup.sh)")
    for name, text in {
        "Team-Msgs": "uint8 mode\n",
        "bad_msgs": "uint8 mode\nstrin g reason\n",
        "geo_msgs": "geographic_msgs/GeoPoint where\nuint8 mode\n",
        "ros1_msgs": "Header header\nuint8 mode\n",
    }.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "State.msg").write_text(text)
    prefix = tmp_path / "prefix"
    result = subprocess.run(
        ["bash", str(ROOT / "scripts/setup.d/50-ros-interfaces.sh")],
        cwd=tmp_path,
        env={**os.environ, "FTT_ROS_PREFIX": str(prefix), "FTT_ROS_INTERFACES": f"{folder}:"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode != 0
    assert says.format(tmp=tmp_path) in result.stderr
    assert "FTT_ROS_INTERFACES: a folder cannot be built" in result.stderr
    assert not prefix.exists()


def test_every_test_that_skips_on_postgis_runs_in_the_spatialite_pass():
    """scripts/test.sh runs on SpatiaLite only the tests marked spatialite, so a
    test that skips on PostGIS and lacks the mark would never run."""
    unmarked = [
        str(path.relative_to(ROOT))
        for path in sorted((ROOT / "tests").rglob("test_*.py"))
        if 'on the embedded database")' in (text := path.read_text())
        and "pytest.mark.spatialite" not in text
    ]
    assert unmarked == []
