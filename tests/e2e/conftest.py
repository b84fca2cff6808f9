"""Browser tests: Debian's Chromium driven by Playwright against a real server.

The server is daphne in a process of its own on the embedded SpatiaLite
default with no broker, and the "robot" writes from yet another process, so
live updates are tested the way they happen in the field.
"""

import io
import os
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from PIL import Image

# Playwright's sync API keeps an event loop in the test thread.
os.environ.setdefault("DJANGO_ALLOW_ASYNC_UNSAFE", "true")

ROOT = Path(__file__).resolve().parents[2]
# Not under test-results/: pytest-playwright empties that folder when a session starts.
ARTIFACTS = Path(os.environ.get("FTT_E2E_ARTIFACTS", ROOT / "test-artifacts" / "e2e"))
PASSWORD = "field-test-2026"


def system_chromium() -> str | None:
    """The distribution's Chromium if it starts (the same test scripts/setup.sh
    makes); None means Playwright's own build, which the setup then fetched."""
    found = subprocess.run(
        ["bash", "-c", f"source {ROOT}/scripts/lib.sh && ftt_working_chromium"],
        capture_output=True,
        text=True,
    )
    if found.returncode != 0:
        return None
    return found.stdout.strip()


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    executable = os.environ.get("FTT_CHROMIUM") or system_chromium()
    return {
        **browser_type_launch_args,
        **({"executable_path": executable} if executable else {}),
        "args": [
            *browser_type_launch_args.get("args", []),
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--disable-quic",
        ],
    }


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """A daphne process plus a way to run Django code in other processes."""

    def __init__(self, data_dir: Path, tile_url: str):
        self.port = _free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {
            k: v for k, v in os.environ.items() if not k.startswith(("FTT_", "DJANGO_ALLOW"))
        }
        self.env.update(
            FTT_DATA_DIR=str(data_dir),
            FTT_TILE_URL=tile_url,
            FTT_ALLOWED_HOSTS="127.0.0.1,localhost",
            DJANGO_SETTINGS_MODULE="ftt_site.settings",
            PYTHONPATH=str(ROOT),
        )
        self.process = None

    def manage(self, *args, timeout=120) -> str:
        result = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=ROOT,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        assert result.returncode == 0, result.stderr[-3000:]
        return result.stdout

    def python(self, code: str) -> str:
        """Run Django code in a separate process (the robot, an admin script)."""
        return self.manage("shell", "-c", textwrap.dedent(code))

    def spawn(self, code: str) -> subprocess.Popen:
        return subprocess.Popen(
            [sys.executable, "manage.py", "shell", "-c", textwrap.dedent(code)],
            cwd=ROOT,
            env=self.env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )

    def start(self):
        self.manage("migrate", "--noinput", timeout=300)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        self.log = open(ARTIFACTS / "daphne.log", "w")  # noqa: SIM115 - open while it runs
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "daphne",
                "-b",
                "127.0.0.1",
                "-p",
                str(self.port),
                "ftt_site.asgi:application",
            ],
            cwd=ROOT,
            env=self.env,
            # Kept as an artifact: when a page hangs, the server's side tells why.
            stdout=self.log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.5):
                    return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("daphne did not start")

    def stop(self):
        if self.process is not None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
            self.log.close()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    server = _running_server
    if report.failed and server is not None and server.process.poll() is None:
        # The server's thread stacks at the moment of failure, in daphne.log.
        server.process.send_signal(signal.SIGUSR1)
    return report


_running_server = None


def _tile_url() -> str:
    # A loopback tile host; tests answer it with page.route or leave it dead.
    return "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png"


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    global _running_server
    srv = Server(tmp_path_factory.mktemp("ftt-e2e"), _tile_url())
    srv.start()
    _running_server = srv
    srv.python(
        f"""
        from django.contrib.auth.models import Group, User
        from events.models import Personnel
        def user(name, role, full):
            u = User.objects.create_user(name, password={PASSWORD!r}, first_name=full)
            u.groups.add(Group.objects.get(name=role))
            return u
        admin = user("ada", "administrator", "Ada Admin")
        admin.is_staff = True
        admin.save()
        op = user("otto", "operator", "Otto Operator")
        Personnel.objects.create(name="Jörg Müller", institution="FKIE", user=op)
        user("vera", "viewer", "Vera Viewer")
        """
    )
    yield srv
    srv.stop()


@pytest.fixture
def shot(request):
    """Save a numbered screenshot of the page as a test artifact."""
    folder = ARTIFACTS / request.node.name
    shutil.rmtree(folder, ignore_errors=True)  # no pictures left from an earlier run
    folder.mkdir(parents=True)
    counter = iter(range(1, 1000))

    def take(page, name: str):
        page.screenshot(path=str(folder / f"{next(counter):02d}-{name}.png"), full_page=True)

    return take


@pytest.fixture
def tiles(page):
    """Answer tile requests with a tiny grey PNG, as a reachable tile server would."""
    buffer = io.BytesIO()
    Image.new("RGB", (256, 256), (200, 200, 200)).save(buffer, format="PNG")
    png = buffer.getvalue()
    page.route("**/tiles/**", lambda route: route.fulfill(body=png, content_type="image/png"))
    return png


def login(page, server, username):
    page.goto(f"{server.url}/login/")
    page.get_by_label("User name").fill(username)
    page.get_by_label("Password").fill(PASSWORD)
    page.get_by_role("button", name="Sign in").click()
    page.wait_for_url(f"{server.url}/")
