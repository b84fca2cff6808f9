"""The durable local queue between receiving and the database.

Every event is appended here (SQLite in WAL mode, on the robot's disk) before
anything tries the database; the writer deletes events only after the
transaction that stored them has committed.  So a database outage, a crash or
a SIGKILL loses at most the events of the last fraction of a second that were
still in memory, and replaying after a crash can only repeat events whose
rows carry the same uid, which the recording services ignore.

The file also keeps a little state (whether logging was on) for a restart.
"""

import json
import sqlite3
import threading
from collections.abc import Callable
from pathlib import Path

from rosbridge_app.collector.disk_guard import disk_full
from rosbridge_app.collector.events import Event

_SCHEMA = """
CREATE TABLE IF NOT EXISTS event (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    kind TEXT NOT NULL,
    at TEXT NOT NULL,
    uid TEXT NOT NULL,
    data TEXT NOT NULL,
    blob BLOB
);
CREATE TABLE IF NOT EXISTS state (key TEXT PRIMARY KEY, value TEXT NOT NULL);
-- Segment changes of a backlog already stored, each with the master it left
-- open (uid or NULL); they stay in the event table as the borders of the
-- backlog's runs until the backlog is written (collector/replay.py).
CREATE TABLE IF NOT EXISTS applied (id INTEGER PRIMARY KEY, master TEXT);
"""


class SpoolFull(Exception):
    """The spool could not be written for want of space (nothing was appended)."""


class Spool:
    def __init__(self, path: Path):
        self.path = Path(path)
        # Frees space when a removal or mark finds the disk full (the reserve,
        # disk_guard.py): what was stored must leave the spool even then.
        self.free_reserve: Callable[[], bool] = lambda: False
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # One connection shared by the threads, serialised by the lock: the
        # statements are short, and SQLite would serialise the writes anyway.
        self._db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None)
        self._lock = threading.Lock()
        with self._lock:
            self._db.execute("PRAGMA journal_mode=WAL")
            # NORMAL in WAL mode survives a process crash (the case we care
            # about); only a power cut may lose the last commits.
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.executescript(_SCHEMA)

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def append(self, events: list[Event]) -> None:
        rows = []
        for event in events:
            kind, at, uid, data, blob = event.to_record()
            rows.append((kind, at, uid, json.dumps(data), blob))
        try:
            self._transaction(
                lambda: self._db.executemany(
                    "INSERT INTO event (kind, at, uid, data, blob) VALUES (?, ?, ?, ?, ?)", rows
                )
            )
        except (sqlite3.Error, OSError) as exc:
            if disk_full(exc):
                raise SpoolFull(str(exc)) from None
            raise

    def _transaction(self, work) -> None:
        with self._lock:
            self._db.execute("BEGIN IMMEDIATE")
            try:
                work()
                self._db.execute("COMMIT")
            except BaseException:
                # A failed COMMIT (disk full) has already rolled back.
                if self._db.in_transaction:
                    try:
                        self._db.execute("ROLLBACK")
                    except sqlite3.Error:
                        pass  # rolled back by SQLite meanwhile
                raise

    def _making_room(self, work) -> None:
        """Run a write the writer needs even on a full disk: once more after
        freeing the reserve."""
        for last in (False, True):
            try:
                return self._transaction(work)
            except sqlite3.Error as exc:
                if not disk_full(exc):
                    raise
                if last or not self.free_reserve():
                    raise SpoolFull(str(exc)) from None

    def reusable(self) -> int:
        """Bytes of free pages inside the file, which new records fill first."""
        with self._lock:
            free = self._db.execute("PRAGMA freelist_count").fetchone()[0]
            size = self._db.execute("PRAGMA page_size").fetchone()[0]
        return free * size

    def peek(
        self,
        limit: int = 500,
        max_bytes: int = 32 * 1024 * 1024,
        *,
        where: str = "1",
        params: tuple = (),
    ) -> list[tuple[int, Event]]:
        """The oldest events (of those ``where`` selects), in order, without removing them."""
        rows, size = [], 0
        with self._lock:
            cursor = self._db.execute(
                "SELECT id, kind, at, uid, data, blob FROM event "
                f"WHERE {where} ORDER BY id LIMIT ?",
                (*params, limit),
            )
            for row in cursor:
                rows.append(row)
                size += len(row[5] or b"") + len(row[4])
                if size >= max_bytes:
                    break
        # One decode for the whole slice: for a position's few fields, a
        # json.loads call of its own costs more than the parsing.
        datas = json.loads("[" + ",".join(row[4] for row in rows) + "]")
        return [
            (row_id, Event.from_record(kind, at, uid, data, blob))
            for (row_id, kind, at, uid, _, blob), data in zip(rows, datas, strict=True)
        ]

    def remove(self, ids: list[int]) -> None:
        if not ids:
            return
        # By id, not by range: the writer may take younger events before older ones.
        self._making_room(
            lambda: self._db.execute(
                "DELETE FROM event WHERE id IN (SELECT value FROM json_each(?))", (json.dumps(ids),)
            )
        )

    def mark_applied(self, marks: list[tuple[int, str | None]]) -> None:
        self._making_room(
            lambda: self._db.executemany(
                "INSERT OR REPLACE INTO applied (id, master) VALUES (?, ?)", marks
            )
        )

    def applied(self) -> list[tuple[int, str | None]]:
        with self._lock:
            return self._db.execute("SELECT id, master FROM applied ORDER BY id").fetchall()

    def forget_applied(self) -> None:
        """The backlog is written: its segment changes leave the spool."""

        def forget():
            self._db.execute("DELETE FROM event WHERE id IN (SELECT id FROM applied)")
            self._db.execute("DELETE FROM applied")

        self._making_room(forget)

    def last_id(self) -> int:
        with self._lock:
            return self._db.execute("SELECT coalesce(max(id), 0) FROM event").fetchone()[0]

    def count_by_kind(self, upto: int) -> dict[str, int]:
        with self._lock:
            rows = self._db.execute(
                "SELECT kind, count(*) FROM event WHERE id <= ? GROUP BY kind ORDER BY 2 DESC",
                (upto,),
            ).fetchall()
        return dict(rows)

    def __len__(self) -> int:
        with self._lock:
            return self._db.execute("SELECT count(*) FROM event").fetchone()[0]

    def get_state(self, key: str, default: str | None = None) -> str | None:
        with self._lock:
            row = self._db.execute("SELECT value FROM state WHERE key = ?", (key,)).fetchone()
        return row[0] if row else default

    def set_state(self, key: str, value: str) -> None:
        self._making_room(
            lambda: self._db.execute(
                "INSERT INTO state (key, value) VALUES (?, ?) "
                "ON CONFLICT (key) DO UPDATE SET value = excluded.value",
                (key, value),
            )
        )
