"""MBTiles archives (plain SQLite) read within a time budget.

An MBTiles file is a database from whoever made it: its ``tiles`` may be a view,
even a recursive one, that takes minutes per row. Every statement here runs
under SQLite's progress handler and is interrupted when its budget is spent;
the caller then gets :class:`TooCostly` instead of holding a request slot.
"""

import sqlite3
import time
from pathlib import Path

# SQLite virtual machine steps between two looks at the clock.
STEPS = 10_000


class TooCostly(Exception):
    """A read that would take longer than its budget; try again later (503)."""


class MBTiles:
    """A read-only connection to one archive whose statements have a time budget."""

    def __init__(self, path: Path):
        self.db = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True, check_same_thread=True)
        self.deadline: float | None = None
        self.db.set_progress_handler(self._passed, STEPS)

    def _passed(self) -> int:
        return int(self.deadline is not None and time.monotonic() > self.deadline)

    def query(self, sql: str, params=(), *, seconds: float) -> list:
        """All rows of ``sql``, or TooCostly after ``seconds``."""
        self.deadline = time.monotonic() + seconds
        try:
            return self.db.execute(sql, params).fetchall()
        except sqlite3.OperationalError:
            if self._passed():
                raise TooCostly(f"the archive did not answer within {seconds:g} s") from None
            raise
        finally:
            self.deadline = None

    def close(self):
        self.db.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
