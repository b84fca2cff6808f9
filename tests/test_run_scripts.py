"""The README's first command as a newcomer types it: FTT on SpatiaLite, with an
administrator, and the demo that adds a simulated robot and its collector."""

import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest
import requests

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(
    "FTT_ROOT" not in os.environ, reason="only under scripts/test.sh, which has run setup"
)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Started:
    """A README script in its own process group, as a terminal would run it."""

    def __init__(self, script: str, data_dir: Path, **env):
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.data_dir = data_dir
        self.log = data_dir / f"{script}.log"
        environment = {
            key: value
            for key, value in os.environ.items()
            # A newcomer has none of these: the embedded database and a new account.
            if key not in {"FTT_DATABASE_URL", "FTT_ADMIN_PASSWORD", "DJANGO_SETTINGS_MODULE"}
        }
        environment.update(FTT_DATA_DIR=str(data_dir), **env)
        self.environment = environment
        data_dir.mkdir(parents=True, exist_ok=True)
        self.process = subprocess.Popen(
            ["bash", f"scripts/{script}", f"127.0.0.1:{self.port}"],
            cwd=ROOT,
            env=environment,
            stdout=self.log.open("wb"),
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )

    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def manage(self, *args: str) -> str:
        """A manage.py command on the same installation, as its administrator would type it."""
        env = {**self.environment, "DJANGO_SETTINGS_MODULE": "ftt_site.settings"}
        python = ROOT / ".venv" / "bin" / "python"
        done = subprocess.run(
            [str(python), "manage.py", *args], cwd=ROOT, env=env, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr[-3000:]
        return done.stdout

    def wait_until_serving(self, timeout: float = 180) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            assert self.process.poll() is None, self.output()
            try:
                if requests.get(f"{self.url}/login/", timeout=2).status_code == 200:
                    return
            except requests.ConnectionError:
                pass
            time.sleep(0.5)
        raise AssertionError(f"not serving after {timeout} s:\n{self.output()}")

    def login(self, username: str, password: str) -> requests.Session:
        browser = requests.Session()
        browser.get(f"{self.url}/login/", timeout=10)
        answer = browser.post(
            f"{self.url}/login/",
            data={
                "username": username,
                "password": password,
                "csrfmiddlewaretoken": browser.cookies["csrftoken"],
            },
            headers={"Referer": f"{self.url}/login/"},
            timeout=10,
        )
        assert answer.ok and answer.url.rstrip("/") == self.url, answer.text[:500]
        return browser

    def stop(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGINT)
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(10)


@pytest.fixture
def started(tmp_path):
    running = []

    def start(script: str, **env) -> Started:
        process = Started(script, tmp_path / "data", **env)
        running.append(process)
        return process

    yield start
    for process in running:
        process.stop()


def administrator_password(process: Started) -> str:
    stored = process.data_dir / "admin_password.txt"
    assert stored.exists(), process.output()
    # The password is printed once for the person at the terminal, and kept.
    password = stored.read_text().strip()
    assert password in process.output()
    return password


def test_run_command_serves_ftt_with_an_administrator_on_spatialite(started):
    ftt = started("run.sh")
    ftt.wait_until_serving()
    assert (ftt.data_dir / "ftt.sqlite3").exists()
    browser = ftt.login("admin", administrator_password(ftt))
    admin = browser.get(f"{ftt.url}/admin/", timeout=10)
    assert admin.status_code == 200 and "FTT administration" in admin.text
    assert browser.get(f"{ftt.url}/admin/events/vehicle/add/", timeout=10).status_code == 200
    gui = browser.get(f"{ftt.url}/", timeout=10)
    assert "Before the first shift" in gui.text  # the first-run hint for administrators


def test_run_command_also_runs_the_job_worker_that_makes_reports(started):
    ftt = started("run.sh")
    ftt.wait_until_serving()
    event_id = ftt.manage(
        "shell",
        "-c",
        "from datetime import UTC, datetime, timedelta\n"
        "from events.models import Vehicle\n"
        "from events.services import logs, segments\n"
        "t = datetime(2026, 5, 4, 9, tzinfo=UTC)\n"
        "v = Vehicle.objects.create(key='husky', short_description='Husky')\n"
        "e = logs.create_test_event(location='Wachtberg', at=t)\n"
        "leg = logs.create_leg(shift=logs.create_shift(test_event=e, vehicle=v, at=t), at=t)\n"
        "segments.report_mode(leg, 'auto', at=t)\n"
        "segments.report_mode(leg, 'ito', at=t + timedelta(minutes=5))\n"
        "logs.close_test_event(e, at=t + timedelta(minutes=9))\n"
        "print(e.pk)",
    ).split()[-1]
    browser = ftt.login("admin", administrator_password(ftt))
    asked = browser.post(
        f"{ftt.url}/api/reports/",
        json={"test_event": int(event_id), "options": {"no_tiles": True}},
        headers={"X-CSRFToken": browser.cookies["csrftoken"]},
        timeout=30,
    )
    assert asked.status_code == 202, asked.text
    deadline = time.monotonic() + 180
    report = asked.json()
    while time.monotonic() < deadline and report["status"] not in ("done", "failed"):
        time.sleep(1)
        report = browser.get(f"{ftt.url}/api/reports/{report['id']}/", timeout=10).json()
    assert report["status"] == "done", (report, ftt.output())
    pdf = browser.get(report["download"], timeout=30)
    assert pdf.content[:4] == b"%PDF"


def test_a_restart_runs_no_checks_and_no_migrations_again(started):
    """The second start of an installation with nothing changed (issue 47, item 2)."""
    first = started("run.sh")
    first.wait_until_serving()
    first.stop()
    start = first.output()
    assert "Applying events.0001_initial" in start
    assert start.count("System check identified") == 1  # once, not per command
    again = started("run.sh")
    again.wait_until_serving()
    restart = again.output()  # the same log file, written anew
    assert "System checks: nothing changed since they last passed." in restart
    assert "Migrations: all applied, none to run." in restart
    assert "Operations to perform" not in restart  # manage.py migrate did not run
    assert "System check identified" not in restart


@pytest.mark.ros
def test_demo_logs_a_simulated_robot_live_into_the_embedded_database(started):
    domain = (int(os.environ.get("ROS_DOMAIN_ID", "10")) + 100) % 230
    ftt = started("demo.sh", ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    ftt.wait_until_serving()
    browser = ftt.login("admin", administrator_password(ftt))
    api = f"{ftt.url}/api"
    deadline = time.monotonic() + 120
    segments = poses = []
    while time.monotonic() < deadline and not (segments and poses):
        segments = browser.get(f"{api}/segments/", timeout=10).json()["results"]
        poses = browser.get(f"{api}/poses/", timeout=10).json()["results"]
        time.sleep(1)
    assert segments and poses, ftt.output() + (ftt.data_dir / "demo-collector.log").read_text()
    events = browser.get(f"{api}/test-events/", timeout=10).json()["results"]
    assert [event["location"] for event in events] == ["Simulation"]
    vehicles = browser.get(f"{api}/vehicles/", timeout=10).json()["results"]
    sim = next(vehicle for vehicle in vehicles if vehicle["key"] == "sim")
    status = browser.get(f"{ftt.url}/gui/api/collectors/?vehicle={sim['id']}", timeout=10)
    collector = status.json()["collector"]
    assert collector["online"] and collector["logging"]
    assert collector["inputs"]["gps_fix"]["count"] > 0
