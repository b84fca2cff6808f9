"""The order in which the writer stores what the spool holds (the one place of that rule).

Normally first in, first out. After an outage (or a start with a full spool)
the spool holds a backlog, and first in, first out kept live data waiting
until all of it was written: a mode switch published after a 2-hour outage
was stored 68 s later. So, once the writer finds more than a quarter of a
slice pending:

* the backlog is what the spool held then (ids up to ``end``);
* segment changes (mode, start, stop) are applied strictly in spool order:
  while the backlog still holds one, the writer goes first in, first out;
* then it keeps two lanes, live first: each turn it stores what arrived after
  ``end`` (up to a slice), then one slice of the backlog. The backlog's
  positions, camera frames and snapshots go onto the master that was open
  after its last segment change, which is where first in, first out would have
  put them, whatever live switches were stored meanwhile; that master's uid is
  kept in the spool, so a restart in the middle continues the same way;
* maps keep their own order (the newest stored is the shift's current map):
  a live map waits in the backlog lane.

So a live switch waits for at most one slice, never for the backlog, and no
record is stored before a segment change that preceded it. A backlog whose
last switch is near its end is written first in, first out up to that switch.
"""

import json
import logging
import time
from dataclasses import dataclass

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.outbox import Outbox
from rosbridge_app.collector.recorder import SEGMENT_CHANGES, Onto, Recorder

_STATE = "backlog"
log = logging.getLogger("ftt.collector")


@dataclass
class Slice:
    rows: list
    onto: Onto | None = None  # None: the open master, as records arrive

    @property
    def backlog(self) -> bool:
        return self.onto is not None


class ReplayOrder:
    """``size``: records per slice; ``backlog``: more pending than this is a backlog."""

    def __init__(self, outbox: Outbox, size: int, backlog: int | None = None):
        self.outbox, self.size = outbox, size
        self.backlog = size // 4 if backlog is None else backlog
        saved = outbox.get_state(_STATE)
        self.lane = json.loads(saved) if saved else None  # {"end": id, "master": uid | None}
        self.end = self.lane["end"] if self.lane else None
        self._found = (time.monotonic(), outbox.count_by_kind(self.end)) if self.lane else None

    @property
    def replaying(self) -> bool:
        return self.lane is not None

    def slices(self, recorder: Recorder) -> list[Slice]:
        if self.end is None and len(self.outbox) > self.backlog:
            self.end = self.outbox.last_id()
            self._found = time.monotonic(), self.outbox.count_by_kind(self.end)
        if self.end is not None and self.lane is None:
            # First in, first out up to the backlog's last segment change.
            if not self.outbox.any_of(SEGMENT_CHANGES, upto=self.end):
                self.lane = {"end": self.end, "master": recorder.open_master_uid()}
                self.outbox.set_state(_STATE, json.dumps(self.lane))
        if self.lane is None:
            rows = self.outbox.peek(self.size)
            if self.end is not None and (not rows or rows[0][0] > self.end):
                self._done()
            return [Slice(rows)]
        end = self.lane["end"]
        live = self.outbox.peek(self.size, where="id > ? AND kind != ?", params=(end, ev.MAP))
        backlog = self.outbox.peek(self.size, where="id <= ? OR kind = ?", params=(end, ev.MAP))
        parts = [Slice(live), Slice(backlog, Onto(self.lane["master"]))]
        if not backlog:
            self.outbox.set_state(_STATE, "")
            self._done()
        return parts

    def _done(self) -> None:
        started, kinds = self._found
        took = max(time.monotonic() - started, 1e-6)
        total = sum(kinds.values())
        # benchmarks/collector_endurance.py reads this line.
        log.info(
            "backlog of %d spooled records stored in %.2f s: %.0f records/s (%s)",
            total,
            took,
            total / took,
            ", ".join(f"{kind} {count} = {count / took:.0f}/s" for kind, count in kinds.items()),
        )
        self.lane = self.end = self._found = None

    def write_next(self, recorder: Recorder) -> int:
        """Store the next slices; how many records were taken from the spool."""
        taken = 0
        for part in self.slices(recorder):
            if not part.rows:
                continue
            recorder.apply([event for _, event in part.rows], onto=part.onto)
            self.outbox.remove([row_id for row_id, _ in part.rows])
            taken += len(part.rows)
        return taken
