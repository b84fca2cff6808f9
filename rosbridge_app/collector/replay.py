"""The order in which the writer stores what the spool holds (the one place of that rule).

Normally first in, first out, and a segment change ends its slice: the
operators' screens wait for its commit, not for the camera frames and
positions spooled after it. When the writer finds more than a quarter of a
slice pending (after an outage, or at a start with a full spool), or finds
records held in memory behind the spool (the disk filled during an outage),
live data must not wait behind it: what the spool holds then is the backlog
(ids up to ``end``), and:

1. its segment changes (mode, start, stop) are applied first, in spool order,
   and each is marked in the spool with the master it left open;
2. then, each turn: one slice of what arrived after the backlog (live data,
   in order, onto the open master), then one slice of the backlog's other
   records, each run between two of its segment changes onto the master the
   earlier one left open (before the first: the master open when the backlog
   was found). That is where first in, first out would have put them,
   whatever live switches were stored meanwhile;
3. maps keep their own order (the newest stored is the shift's current map):
   a live map waits in the backlog lane.

Records held in memory while the spool could not be written (held.py) are
younger than everything in the spool: they are live data, taken when the
spool has no live records (their maps after the backlog).

So a live switch waits for the backlog's few segment changes and one slice,
never for the backlog, and no segment change is applied before one that
preceded it. The marks and the backlog's bounds live in the spool, so a
restart in the middle goes on the same way.

A backlog slice grows (up to ``MAX_SLICES`` live slices) while it is stored
in less than ``SLICE_SECONDS``: a slice costs a few dozen round trips to the
database whatever its size. That time is also how long a live switch may wait:
a slice of many runs (segment changes) ends once it is spent.
docs/collector.md ("Nothing is lost") has the figures.
"""

import bisect
import itertools
import json
import logging
import time

from django.utils.translation import gettext

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.event_writer import EventWriter, GivenMaster
from rosbridge_app.collector.held import Held
from rosbridge_app.collector.spool import Spool

_STATE = "backlog"
SLICE_SECONDS = 0.5
MAX_SLICES = 10
log = logging.getLogger("ftt.collector")


def _up_to_change(rows: list) -> list:
    """The rows up to and with the first segment change."""
    for i, (_, event) in enumerate(rows):
        if event.kind in ev.SEGMENT_CHANGES:
            return rows[: i + 1]
    return rows


class ReplayOrder:
    """``size``: records per slice; ``backlog``: more pending than this is a backlog."""

    def __init__(
        self, spool: Spool, size: int, backlog: int | None = None, held: Held | None = None
    ):
        self.spool, self.size, self.held = spool, size, held
        self.backlog = size // 4 if backlog is None else backlog
        self.backlog_slice = size  # records per backlog slice, see SLICE_SECONDS
        # Set once the backlog's segment changes are all applied: looking for
        # more would scan the whole backlog every turn.
        self._changes_done = False
        self.stored_change = False  # whether the last write_next stored a segment change
        saved = spool.get_state(_STATE)
        # {"end": last id of the backlog, "master": uid open before it, or None}
        self.lane = json.loads(saved) if saved else None
        self._found = (
            (time.monotonic(), spool.count_by_kind(self.lane["end"])) if self.lane else None
        )

    @property
    def replaying(self) -> bool:
        return self.lane is not None

    def write_next(self, event_writer: EventWriter) -> int:
        """Store the next slices; how many records were taken or marked."""
        self.stored_change = False
        if self.lane is None and self._has_backlog():
            self._changes_done = False
            self.backlog_slice = self.size
            end = self.spool.last_id()
            self._found = time.monotonic(), self.spool.count_by_kind(end)
            self.lane = {"end": end, "master": event_writer.open_master_uid()}
            self.spool.set_state(_STATE, json.dumps(self.lane))
        if self.lane is None:
            taken = self._store(event_writer, _up_to_change(self.spool.peek(self.size)), None)
            return taken or self._store_held(event_writer, maps=True)
        end = self.lane["end"]
        kinds = sorted(ev.SEGMENT_CHANGES)
        if not self._changes_done:
            changes = self.spool.peek(
                self.size,
                where=f"id <= ? AND kind IN ({', '.join('?' * len(kinds))}) "
                "AND id NOT IN (SELECT id FROM applied)",
                params=(end, *kinds),
            )
            if changes:
                masters = event_writer.apply_changes([event for _, event in changes])
                ids = [row_id for row_id, _ in changes]
                self.spool.mark_applied(list(zip(ids, masters, strict=True)))
                self.stored_change = True
                return len(changes)
            self._changes_done = True
        live = self.spool.peek(self.size, where="id > ? AND kind != ?", params=(end, ev.MAP))
        taken = self._store(event_writer, live, None) or self._store_held(event_writer, maps=False)
        started = time.monotonic()
        backlog = self.spool.peek(
            self.backlog_slice,
            where="(id <= ? AND id NOT IN (SELECT id FROM applied)) OR (id > ? AND kind = ?)",
            params=(end, end, ev.MAP),
        )
        if not backlog:
            self.spool.forget_applied()
            self.spool.set_state(_STATE, "")
            self._done()
            return taken or self._store_held(event_writer, maps=True)
        marks = self.spool.applied()
        borders = [row_id for row_id, _ in marks]
        runs = itertools.groupby(backlog, key=lambda row: bisect.bisect(borders, row[0]))
        stored = 0
        for run, rows in runs:
            master = marks[run - 1][1] if run else self.lane["master"]
            stored += self._store(event_writer, list(rows), GivenMaster(master))
            if time.monotonic() - started > SLICE_SECONDS:
                break  # each run costs its round trips: live data waits no longer
        if stored == self.backlog_slice:  # a short slice (the last, or maps) tells nothing
            rate = stored / max(time.monotonic() - started, 1e-3)
            self.backlog_slice = int(
                min(self.size * MAX_SLICES, max(self.size, rate * SLICE_SECONDS))
            )
        return taken + stored

    def _has_backlog(self) -> bool:
        pending = len(self.spool)
        # Held records are younger than the whole spool: behind it, they would
        # wait for each of its segment changes' round trips.
        return pending > self.backlog or bool(pending and self.held is not None and len(self.held))

    def _store(self, event_writer: EventWriter, rows: list, master: GivenMaster | None) -> int:
        if rows:
            event_writer.apply([event for _, event in rows], master=master)
            self.spool.remove([row_id for row_id, _ in rows])
            self.stored_change |= any(event.kind in ev.SEGMENT_CHANGES for _, event in rows)
        return len(rows)

    def _store_held(self, event_writer: EventWriter, maps: bool) -> int:
        if self.held is None or not len(self.held):
            return 0
        with self.held.lock:
            events = self.held.peek(self.size, maps=maps)
        if events:
            # Not under the lock: the spool thread goes on holding meanwhile. Should it
            # move these to the spool too, they are stored again later as nothing (uids).
            event_writer.apply(events)
            self.stored_change |= any(event.kind in ev.SEGMENT_CHANGES for event in events)
            with self.held.lock:
                self.held.remove(events)
        return len(events)

    def _done(self) -> None:
        started, kinds = self._found
        took = max(time.monotonic() - started, 1e-6)
        total = sum(kinds.values())
        # benchmarks/collector_endurance.py reads this line.
        log.info(
            gettext("backlog of %d spooled records stored in %.2f s: %.0f records/s (%s)"),
            total,
            took,
            total / took,
            ", ".join(f"{kind} {count} = {count / took:.0f}/s" for kind, count in kinds.items()),
        )
        self.lane = self._found = None
