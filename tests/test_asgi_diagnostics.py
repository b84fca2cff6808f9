"""A web server that stopped answering can be asked where it is stuck."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run_python(code: str, data_dir: Path) -> subprocess.CompletedProcess:
    """``code`` in a Python process of its own with FTT's settings."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("FTT_")}
    env.update(FTT_DATA_DIR=str(data_dir), DJANGO_SETTINGS_MODULE="ftt_site.settings")
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60
    )


@pytest.mark.skipif(not hasattr(signal, "SIGUSR1"), reason="POSIX signal")
def test_sigusr1_prints_every_thread_stack_and_keeps_running(tmp_path):
    code = (
        "import os, signal, sys, time\n"
        "import ftt_site.asgi\n"
        "os.kill(os.getpid(), signal.SIGUSR1)\n"
        "time.sleep(0.5)\n"
        "print('still running', flush=True)\n"
    )
    result = run_python(code, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "still running" in result.stdout
    assert "most recent call first" in result.stderr


def test_a_blocked_event_loop_is_reported_once_with_the_blocking_stack(tmp_path):
    import asyncio
    import logging
    import threading
    import time

    from ftt_site.server.loop_watch import watch_loop

    said, again = [], threading.Event()

    class Heard(logging.Handler):
        def emit(self, record):
            said.append(record.getMessage())
            if "runs again" in said[-1]:
                again.set()

    logger, heard = logging.getLogger("ftt.web"), Heard()
    logger.addHandler(heard)
    loop = asyncio.new_event_loop()
    runner = threading.Thread(target=loop.run_forever, daemon=True)
    runner.start()

    def block_the_loop():
        time.sleep(2.5)

    dump = tmp_path / "stacks.txt"
    try:
        with dump.open("w") as file:
            watch_loop(loop, stall_s=0.5, file=file)
            loop.call_soon_threadsafe(block_the_loop)
            assert again.wait(15), said
    finally:
        logger.removeHandler(heard)
        loop.call_soon_threadsafe(loop.stop)
        runner.join(5)
        loop.close()
    assert sum("has run nothing" in m for m in said) == 1, said
    assert sum("runs again after" in m for m in said) == 1, said
    assert "in block_the_loop" in dump.read_text()


def test_the_server_application_starts_the_watch_with_its_event_loop(tmp_path):
    code = (
        "import asyncio, threading\n"
        "from ftt_site.asgi import application\n"
        "async def main():\n"
        "    inbox, said = asyncio.Queue(), asyncio.Queue()\n"
        "    scope = {'type': 'lifespan', 'asgi': {'version': '3.0'}}\n"
        "    serving = asyncio.create_task(application(scope, inbox.get, said.put))\n"
        "    await inbox.put({'type': 'lifespan.startup'})\n"
        "    print((await said.get())['type'])\n"
        "    print('watching' if any(t.name == 'loop-watch' for t in threading.enumerate())"
        " else 'not watching')\n"
        "    await inbox.put({'type': 'lifespan.shutdown'})\n"
        "    print((await said.get())['type'])\n"
        "    await serving\n"
        "asyncio.run(main())\n"
    )
    result = run_python(code, tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split() == [
        "lifespan.startup.complete",
        "watching",
        "lifespan.shutdown.complete",
    ]
