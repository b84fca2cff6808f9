"""A web server that stopped answering can be asked where it is stuck."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(not hasattr(signal, "SIGUSR1"), reason="POSIX signal")
def test_sigusr1_prints_every_thread_stack_and_keeps_running(tmp_path):
    code = (
        "import os, signal, sys, time\n"
        "import ftt_site.asgi\n"
        "os.kill(os.getpid(), signal.SIGUSR1)\n"
        "time.sleep(0.5)\n"
        "print('still running', flush=True)\n"
    )
    env = {k: v for k, v in os.environ.items() if not k.startswith("FTT_")}
    env.update(FTT_DATA_DIR=str(tmp_path), DJANGO_SETTINGS_MODULE="ftt_site.settings")
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "still running" in result.stdout
    assert "most recent call first" in result.stderr
