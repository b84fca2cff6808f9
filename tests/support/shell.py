"""One ``manage.py shell`` kept running for a test's Django code snippets.

Each snippet runs as ``manage.py shell -c`` runs it (a fresh namespace, its
printed output returned, a failure raised with its traceback), in a process
apart from the test and the server, but without a new interpreter and Django
set-up for every snippet. Between snippets the process forgets
what a new one would not have: database connections, per-process caches, the
active language.
"""

import json
import queue
import subprocess
import sys
import threading
from pathlib import Path

ANSWER = "\x1eftt-shell-answer "

# Runs inside the shell: one request per line on stdin, one answer line on stdout.
SERVE = f"""
import contextlib, io, json, sys, traceback
from django.conf import settings
from django.core.cache import caches
from django.db import connections
from django.utils import timezone, translation
from tests.support.caches import forget_memos

# What `shell -c` puts in scope (its automatic imports), for every snippet.
scope = {{name: value for name, value in globals().items() if not name.startswith("_")}}
pipe, answers = sys.stdin, sys.stdout
for line in iter(pipe.readline, ""):
    request = json.loads(line)
    printed, ok = io.StringIO(), True
    sys.stdin = io.StringIO(request["stdin"] or "")
    try:
        with contextlib.redirect_stdout(printed):
            exec(compile(request["code"], "<snippet>", "exec"), {{**scope, "__name__": "__main__"}})
    except BaseException:  # a snippet's sys.exit ends the snippet, not the shell
        ok = False
        printed.write(traceback.format_exc())
    finally:
        sys.stdin = pipe
        connections.close_all()
        forget_memos()
        caches["default"].clear()
        translation.activate(settings.LANGUAGE_CODE)
        timezone.deactivate()
    answers.write({ANSWER!r} + json.dumps({{"ok": ok, "printed": printed.getvalue()}}) + "\\n")
    answers.flush()
"""


class DjangoShell:
    def __init__(self, root: Path, env: dict):
        self.process = subprocess.Popen(
            [sys.executable, "manage.py", "shell", "--verbosity", "0", "-c", SERVE],
            cwd=root,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        self._lines: queue.Queue = queue.Queue()
        self._stderr: list[str] = []
        threading.Thread(
            target=self._read, args=(self.process.stdout, self._lines), daemon=True
        ).start()
        threading.Thread(target=self._keep_stderr, daemon=True).start()

    @staticmethod
    def _read(stream, lines: queue.Queue) -> None:
        for line in stream:
            lines.put(line)
        lines.put(None)

    def _keep_stderr(self) -> None:
        for line in self.process.stderr:
            self._stderr = [*self._stderr[-200:], line]

    def run(self, code: str, stdin: str | None = None, timeout: float = 300) -> str:
        """What ``code`` printed; AssertionError with its traceback when it failed."""
        self.process.stdin.write(json.dumps({"code": code, "stdin": stdin}) + "\n")
        self.process.stdin.flush()
        printed = []
        while True:
            try:
                line = self._lines.get(timeout=timeout)
            except queue.Empty:
                self.close()
                raise AssertionError(f"the snippet did not end within {timeout} s") from None
            if line is None:
                raise AssertionError("the Django shell ended:\n" + "".join(self._stderr)[-3000:])
            if line.startswith(ANSWER):
                answer = json.loads(line[len(ANSWER) :])
                printed.append(answer["printed"])
                text = "".join(printed)
                assert answer["ok"], text[-3000:]
                return text
            printed.append(line)  # written past sys.stdout, e.g. by a child process

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.stdin.close()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
