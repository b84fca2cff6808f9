"""The collector's disk budget: how full the robot's disk may get, and what is
given up when it is full (the one place of that rule; docs/collector.md,
"A full disk").

Everything the collector writes (the spool, its write-ahead log, pending
snapshot files) counts against ``spool.disk_budget_mb``, and the file system
must keep ``spool.disk_headroom_mb`` free for the rest of the robot. Checked
before every write, it degrades in this order:

* ``TIGHT`` (90 % of the budget, or less than twice the headroom free):
  snapshots are dropped, and camera frames while the database does not answer
  (the spooler asks); everything else is still spooled;
* ``FULL`` (budget or headroom reached, or a write failed for want of space):
  nothing more goes to disk; :mod:`~rosbridge_app.collector.held` keeps mode
  switches and segment changes, the latest map and positions thinned to the
  report's resolution in memory until the database or the disk takes them.

A reserve file of ``RESERVE_BYTES`` is kept beside the spool: when the disk is
full it is deleted, so that the writer can still remove what it has stored
and mark segment changes (SQLite needs a little space even to delete).
Each change of state is logged once, with what was given up meanwhile.
"""

import logging
import os
import shutil
import threading
import time
from pathlib import Path

from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

log = logging.getLogger("ftt.collector")

MB = 1024 * 1024
OK, TIGHT, FULL = 0, 1, 2
TIGHT_SHARE = 0.9
RESERVE_BYTES = 2 * MB
# A level is left only with this much room to spare.
HYSTERESIS_BYTES = 1 * MB
# Sizing the snapshot directory walks it: at most this often.
SCAN_EVERY_S = 1.0
# After a write failed for want of space the disk is tried again no sooner.
RETRY_S = 1.0


def disk_full(exc: BaseException) -> bool:
    """Whether a failed write failed for want of space (SQLite or the OS)."""
    import errno
    import sqlite3

    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return True
    code = getattr(exc, "sqlite_errorcode", None)
    if code is not None:
        return code & 0xFF in (sqlite3.SQLITE_FULL, sqlite3.SQLITE_IOERR)
    return isinstance(exc, sqlite3.OperationalError) and "full" in str(exc)


# What the guard gives up, as the summary names it.
GIVEN_UP = {
    "frames": gettext_noop("camera frames"),
    "snapshots": gettext_noop("snapshots"),
    "positions": gettext_noop("positions"),
    "maps": gettext_noop("maps"),
}


class DiskGuard:
    """``budget``/``headroom`` in bytes (None: no budget). ``used`` tells the
    spool's bytes in use and ``reusable`` its free pages (a file that shrank
    inside keeps its size)."""

    def __init__(self, spool: Path, budget: int | None = None, headroom: int = 0):
        self.spool = Path(spool)
        self.snapshots: Path | None = None
        self.budget, self.headroom = budget, headroom
        self.reserve_path = self.spool.with_name(self.spool.name + ".reserve")
        self.reusable = lambda: 0
        self.level = OK
        self.cause = ""
        self.since: float | None = None  # wall clock of the first degradation
        self.given_up = {"frames": 0, "snapshots": 0, "positions": 0, "maps": 0}
        self._snap_bytes, self._scanned = 0, 0.0
        self._failed_at = 0.0
        self.failed_writes = 0  # summarised on the way back, never logged one by one
        self._lock = threading.Lock()

    def configure(self, budget_mb: float, headroom_mb: float) -> None:
        self.budget, self.headroom = int(budget_mb * MB), int(headroom_mb * MB)

    # --- measuring ----------------------------------------------------------------------

    def _spool_bytes(self) -> int:
        total = 0
        for suffix in ("", "-wal", "-shm"):
            try:
                total += os.stat(f"{self.spool}{suffix}").st_size
            except OSError:
                pass
        return max(0, total - self.reusable())

    def _snapshot_bytes(self) -> int:
        if self.snapshots is None or time.monotonic() - self._scanned < SCAN_EVERY_S:
            return self._snap_bytes
        self._scanned = time.monotonic()
        total = 0
        try:
            for entry in os.scandir(self.snapshots):
                try:
                    total += entry.stat().st_size
                except OSError:
                    pass
        except OSError:
            pass
        self._snap_bytes = total
        return total

    def measure(self, extra: int = 0) -> tuple[int, str]:
        """The level writing ``extra`` more bytes would leave, and why."""
        try:
            free = shutil.disk_usage(self.spool.parent).free + self.reusable()
        except OSError:
            free = None
        used = self._spool_bytes() + self._snapshot_bytes() + extra
        if self.budget is not None and used >= self.budget:
            return FULL, _("disk budget of %(mb).0f MB used") % {"mb": self.budget / MB}
        if free is not None and free - extra < self.headroom:
            return FULL, _("%(free).1f MB free, %(mb).0f MB kept for the robot") % {
                "free": free / MB,
                "mb": self.headroom / MB,
            }
        if self.budget is not None and used >= TIGHT_SHARE * self.budget:
            return TIGHT, _("disk budget nearly used")
        if free is not None and free - extra < 2 * self.headroom:
            return TIGHT, _("disk nearly full")
        return OK, ""

    # --- state --------------------------------------------------------------------------

    def check(self, extra: int = 0) -> int:
        """The level now (a FULL reached by a failed write stays until there is room)."""
        level, cause = self.measure(extra)
        if level < self.level and self.measure(extra + HYSTERESIS_BYTES)[0] > level:
            level = self.level  # not back yet: without a margin it would flap
        if self.level == FULL and self.cause.startswith("!") and level < FULL:
            # Left by a failed write: back only with room for the reserve too.
            if (
                time.monotonic() - self._failed_at < RETRY_S
                or self.measure(extra + RESERVE_BYTES)[0] == FULL
            ):
                return FULL
        self._set(level, cause)
        return self.level

    def failed(self, exc: BaseException) -> None:
        """A write failed for want of space: FULL until ``check`` finds room."""
        self.release_reserve()
        self._failed_at = time.monotonic()
        with self._lock:
            self.failed_writes += 1
        self._set(FULL, "!" + str(exc).strip())

    def count(self, what: str, n: int = 1) -> None:
        with self._lock:
            self.given_up[what] += n

    def _set(self, level: int, cause: str) -> None:
        with self._lock:
            if level == self.level:
                if level:
                    self.cause = cause if not self.cause.startswith("!") else self.cause
                return
            before, self.level, self.cause = self.level, level, cause
            if level and self.since is None:
                self.since = time.time()
        if level > before:
            line = (
                _("robot disk full (%s): %s")
                if level == FULL
                else _("robot disk nearly full (%s): %s")
            )
            log.warning(line, cause.lstrip("!"), _tiers(level))
            return
        summary = self.summary()
        if level == OK:
            with self._lock:
                self.since = None
                self.given_up = dict.fromkeys(self.given_up, 0)
                self.failed_writes = 0
            self.make_reserve()
        again = (
            _("robot disk nearly full again: %s") if level else _("robot disk has room again: %s")
        )
        log.warning(again, summary)

    def summary(self) -> str:
        counts = ", ".join(
            (
                _("%(count)s %(what)s thinned out")
                if what == "positions"
                else _("%(count)s %(what)s dropped")
            )
            % {"count": n, "what": _(GIVEN_UP[what])}
            for what, n in self.given_up.items()
            if n
        )
        since = time.strftime("%H:%M:%S", time.localtime(self.since)) if self.since else "-"
        failed = (
            _("; %(count)s writes to the spool failed") % {"count": self.failed_writes}
            if self.failed_writes
            else ""
        )
        return _("since %(since)s: %(counts)s%(failed)s") % {
            "since": since,
            "counts": counts or _("nothing dropped"),
            "failed": failed,
        }

    def describe(self) -> str:
        """For the cockpit's robot panel: empty while there is room."""
        if self.level == OK and not any(self.given_up.values()):
            return ""
        since = time.strftime("%H:%M", time.localtime(self.since)) if self.since else ""
        g = self.given_up
        parts = []
        if self.level == FULL:
            head = _("robot disk full since %(since)s") % {"since": since}
        else:
            head = _("robot disk nearly full since %(since)s") % {"since": since}
        if g["snapshots"]:
            parts.append(_("%(n)d snapshots dropped") % {"n": g["snapshots"]})
        if g["frames"]:
            parts.append(_("%(n)d camera frames dropped") % {"n": g["frames"]})
        if g["positions"]:
            parts.append(_("%(n)d positions thinned out") % {"n": g["positions"]})
        return ", ".join([head, *parts])

    # --- the reserve --------------------------------------------------------------------

    def make_reserve(self) -> None:
        if self.reserve_path.exists():
            return
        try:
            with open(self.reserve_path, "wb") as f:
                os.posix_fallocate(f.fileno(), 0, RESERVE_BYTES)
        except OSError:
            self.reserve_path.unlink(missing_ok=True)

    def release_reserve(self) -> bool:
        try:
            self.reserve_path.unlink()
            return True
        except FileNotFoundError:
            return False


def _tiers(level: int) -> str:
    if level == TIGHT:
        return _(
            "snapshots are dropped, and camera frames while the database does not answer; "
            "everything else is spooled"
        )
    return _(
        "nothing more is spooled; mode switches and segment changes, the latest map and "
        "positions are kept in memory (positions thinned to the report's resolution and "
        "camera frames dropped while the database does not answer)"
    )
