"""The production server for tests and benchmarks, started as scripts/run.sh starts it.

:class:`WebServer` runs Gunicorn with FTT's Uvicorn workers
(``ftt_site/server/gunicorn.conf.py``) on loopback, in a process group of its own, and
runs ``manage.py`` commands against the same installation.
"""

import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import requests

from tests.support.shell import DjangoShell
from tests.support.sites import copy_migrated_database

ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def end(process: subprocess.Popen | None, timeout: float) -> None:
    """SIGTERM, and SIGKILL when it is still running ``timeout`` seconds later."""
    if process is None or process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


class WebServer:
    """``gunicorn -c ftt_site/server/gunicorn.conf.py ftt_site.asgi:application`` on a free port.

    ``env`` adds FTT settings to a copy of this process's environment without its
    own ``FTT_*`` ones; ``root``: the checkout whose code runs (a benchmark compares two).
    """

    def __init__(self, env: dict, workers: int = 1, log: Path | None = None, root: Path = ROOT):
        self.root = root
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {
            k: v for k, v in os.environ.items() if not k.startswith(("FTT_", "DJANGO_ALLOW"))
        }
        self.env.update(
            DJANGO_SETTINGS_MODULE="ftt_site.settings",
            FTT_ALLOWED_HOSTS="127.0.0.1,localhost",
            PYTHONPATH=str(root),
            **env,
        )
        self.workers = workers
        self.log_path = log
        self.process = None
        self._shell = None

    def manage(self, *args, stdin: str | None = None, timeout: float = 300) -> str:
        result = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=self.root,
            env=self.env,
            input=stdin,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        assert result.returncode == 0, result.stderr[-3000:]
        return result.stdout

    def python(self, code: str, stdin: str | None = None, timeout: float = 300) -> str:
        """Run Django code in a separate process (a robot, an admin script): a
        Django shell kept for this server (tests/support/shell.py)."""
        if self._shell is None or self._shell.process.poll() is not None:
            self._shell = DjangoShell(self.root, self.env)
        return self._shell.run(textwrap.dedent(code), stdin=stdin, timeout=timeout)

    def start(self, migrate: bool = True):
        data_dir = self.env.get("FTT_DATA_DIR")
        # The copy is of this checkout's migrations; another root migrates its own.
        embedded = data_dir and not self.env.get("FTT_DATABASE_URL") and self.root == ROOT
        if migrate and embedded and not (Path(data_dir) / "ftt.sqlite3").exists():
            copy_migrated_database(Path(data_dir))
        elif migrate:
            self.manage("migrate", "--noinput")
        self.log = open(self.log_path or os.devnull, "w")  # noqa: SIM115 - open while it runs
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "gunicorn",
                "-c",
                str(self.root / "ftt_site" / "server" / "gunicorn.conf.py"),
                "--bind",
                f"127.0.0.1:{self.port}",
                "--workers",
                str(self.workers),
                "ftt_site.asgi:application",
            ],
            cwd=self.root,
            env=self.env,
            # Kept: when a page hangs, the server's side tells why.
            stdout=self.log,
            stderr=subprocess.STDOUT,
            # As a terminal runs it: Ctrl-C there reaches the whole group.
            start_new_session=True,
        )
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"the web server exited (log: {self.log_path})")
            try:
                if requests.get(f"{self.url}/login/", timeout=2).status_code == 200:
                    return self
            except requests.RequestException:
                pass
            time.sleep(0.3)
        raise RuntimeError("the web server did not start")

    def interrupt(self, group: bool = False) -> None:
        """SIGINT to the master (``kill -INT``), or to its whole process group as
        Ctrl-C in a terminal sends it."""
        if group:
            os.killpg(self.process.pid, signal.SIGINT)
        else:
            self.process.send_signal(signal.SIGINT)

    def stop(self):
        if self._shell is not None:
            self._shell.close()
            self._shell = None
        if self.process is not None:
            end(self.process, 20)
            self.log.close()
