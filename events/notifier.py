"""One NOTIFY, sent soon, for many commits that left it to their process.

A commit that NOTIFYs holds PostgreSQL's notify lock until its WAL flush
ends, so such commits cannot share a flush (group commit).  A single stored
pose, a commit of its own many times a second, tells the feed's trigger to
skip its NOTIFY (``LATER`` in its statement, events migration 0010) and,
once committed, calls :func:`notify_soon`.  One thread per process then
sends ``NOTIFY`` on its own connection for every call of the last few
milliseconds together.  The readers poll the feed anyway (FTT_LIVE_POLL_MS),
so a NOTIFY lost with a process that dies in between delays them by at most
one poll interval.
"""

import logging
import os
import threading
import time

import psycopg
from django.conf import settings

from common.sql import conninfo
from events.feed import CHANNEL

logger = logging.getLogger(__name__)

# SQL for a statement's select list: this transaction's feed rows do not
# NOTIFY from the trigger; the writer calls notify_soon() after its commit.
LATER = "set_config('ftt.notify_later', 'on', true)"
# After a failed NOTIFY the thread waits this long before it connects again.
RETRY = 1.0


class Notifier:
    """Sends ``NOTIFY`` on the feed's channel after every :meth:`poke`, once for
    all pokes that arrive while it waits or sends.  :meth:`poke` never blocks
    and never fails: the thread and its connection start with the first one."""

    def __init__(self, delay: float):
        self.delay = delay
        self._poked = threading.Event()
        self._lock = threading.Lock()
        # Held while the connection is used, by the thread or by disconnect().
        self._using = threading.Lock()
        self._connection = None
        self._pid = None

    def poke(self) -> None:
        self._poked.set()
        # A forked child has the parent's state but not its thread.
        if self._pid == os.getpid():
            return
        with self._lock:
            if self._pid == os.getpid():
                return
            try:
                thread = threading.Thread(target=self._run, name="ftt-notify", daemon=True)
                thread.start()
            except RuntimeError as exc:  # the interpreter is shutting down
                logger.warning("live NOTIFY thread not started: %s", exc)
                return
            self._pid = os.getpid()

    def _run(self) -> None:
        while True:
            self._poked.wait()
            time.sleep(self.delay)
            try:
                self._send()
            except Exception as exc:  # noqa: BLE001 - the readers poll meanwhile
                logger.warning("live NOTIFY not sent: %s", exc)
                self._close()
                self._poked.set()
                time.sleep(RETRY)

    def _send(self) -> None:
        with self._using:
            # Cleared before sending: a poke from now on gets a NOTIFY of its own.
            self._poked.clear()
            if self._connection is None or self._connection.closed:
                self._connection = psycopg.connect(conninfo(), autocommit=True)
            self._connection.execute(f"NOTIFY {CHANNEL}")

    def disconnect(self, wait: float = 1.0) -> None:
        """Send what is due, then close the connection (the next NOTIFY opens
        another): before a test database is dropped."""
        until = time.monotonic() + wait
        while self._poked.is_set() and self._pid == os.getpid() and time.monotonic() < until:
            time.sleep(self.delay or 0.001)
        self._close()

    def _close(self) -> None:
        with self._using:
            if self._connection is not None:
                self._connection.close()
                self._connection = None


_notifier = Notifier(settings.FTT_LIVE_NOTIFY_DELAY_MS / 1000)


def notify_soon() -> None:
    """Wake the feed's readers soon after this commit (see the module's doc)."""
    _notifier.poke()


def disconnect() -> None:
    _notifier.disconnect()
