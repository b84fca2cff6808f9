"""The Gunicorn worker of FTT's production server (ftt_site/gunicorn.conf.py).

Uvicorn's worker for Gunicorn, with one difference: the supervisor's quick-stop
signal stops it.  Gunicorn's master answers SIGINT (Ctrl-C) and SIGQUIT by
sending its workers SIGQUIT, which Uvicorn's worker only notes without stopping
its server; the master then waited its whole graceful timeout before killing
it, also when nothing was in flight.  Here SIGQUIT becomes the SIGTERM that
Uvicorn's server stops on: it closes the listening socket, idle keep-alive
connections and websockets (code 1012, "service restart": the live pages
reconnect) at once, lets requests in flight finish, and exits; the master's
graceful timeout bounds how long those may take.
"""

import signal

from uvicorn_worker import UvicornWorker


class Worker(UvicornWorker):
    def handle_exit(self, sig, frame):
        super().handle_exit(sig, frame)
        if sig == signal.SIGQUIT:
            signal.raise_signal(signal.SIGTERM)
