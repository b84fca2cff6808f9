"""Gunicorn settings for FTT's production server: ``gunicorn -c ftt_site/server/gunicorn.conf.py``.

Gunicorn supervises the processes (restarts a crashed one, graceful reloads);
each runs Uvicorn, which streams request bodies to the application with flow
control instead of buffering them (Daphne reads a whole body into memory
first). README's production section explains the choice and the budget.
"""

import faulthandler
import gc
import os
import shutil
import signal
import tempfile

# Every worker writes its metric values here; /metrics adds them up
# (ftt_site.monitoring.metrics). Set before the application, and prometheus_client, load.
# In memory where there is /dev/shm: the values are memory-mapped files written
# at every request.
os.environ["PROMETHEUS_MULTIPROC_DIR"] = tempfile.mkdtemp(
    prefix="ftt-metrics-", dir="/dev/shm" if os.path.isdir("/dev/shm") else None
)

bind = os.environ.get("FTT_BIND", "127.0.0.1:8000")
workers = int(os.environ.get("FTT_WEB_WORKERS", "2"))
# Uvicorn that stops at once when idle and limits the time for request headers
# (ftt_site/server/web_worker.py).
worker_class = "ftt_site.server.web_worker.Worker"
# A worker that has not answered its supervisor for this long is replaced.
timeout = 120
# On Ctrl-C or SIGTERM an idle worker stops at once (ftt_site/server/web_worker.py);
# requests in flight get this long to finish.
graceful_timeout = 30
# FTT does not use gunicornc; its default socket path is one per user, shared
# by every server that user starts on the machine.
control_socket_disable = True
# The websocket of an idle browser stays open; keep-alive for its API calls.
# An idle keep-alive connection is closed after this many seconds.
keepalive = 5
accesslog = os.environ.get("FTT_ACCESS_LOG") or None
# Load Django once before forking: the address is bound only when the
# application is ready (no connections accepted and left unanswered while a
# worker imports), and the workers share the loaded code. Not when debugging:
# scripts/run.sh then passes --reload, which needs the code loaded per worker.
preload_app = os.environ.get("FTT_DEBUG", "0").lower() not in ("1", "true", "yes", "on")


def on_starting(server):
    """Runs after the preload, before the address is bound.

    The preloaded application warmed itself up (ftt_site.server.warmup: the views
    imported, the first pages' templates compiled), so the forked workers start
    with all of it.
    """
    if not server.cfg.preload_app:
        return
    # Everything loaded so far lives as long as the process.  Frozen, it is left
    # out of the cyclic collector's full passes, which large batches would
    # otherwise trigger often; the forked workers inherit the frozen set, and
    # their pages of it stay shared.
    gc.freeze()


def child_exit(server, worker):
    """A dead worker's live gauges no longer count."""
    from prometheus_client import multiprocess

    multiprocess.mark_process_dead(worker.pid)


def on_exit(server):
    shutil.rmtree(os.environ["PROMETHEUS_MULTIPROC_DIR"], ignore_errors=True)


def post_worker_init(worker):
    """`kill -USR1` on a worker, or on the master that passes it on, prints every
    thread's stack (as ftt_site/asgi.py promises) and then reopens the log files
    as Gunicorn does: Gunicorn's own USR1 handler replaced the one asgi.py set.

    The server's error and access logs (Uvicorn's lines go to them too) get the
    filter that masks robot tokens in /legacy/ paths."""
    faulthandler.register(signal.SIGUSR1, all_threads=True, chain=True)
    from ftt_site.inbound.log_masks import MaskRobotTokens

    for handler in {*worker.log.error_log.handlers, *worker.log.access_log.handlers}:
        handler.addFilter(MaskRobotTokens())
