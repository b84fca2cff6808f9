"""Messages lost on the way, estimated from the robot's stamps.  Free of ROS.

A topic published at a steady rate whose stamps jump by k periods lost k - 1
messages between them (in DDS, in a full history while the collector was
starved, or on the robot).  The rate is measured, not configured: the median
of the recent ordinary intervals.  A silence longer than PAUSE is the robot
not publishing (no fix, a paused bag), not a loss.
"""

import statistics
from collections import deque

# An interval this many times the period holds a missed message.
LATE = 1.5
# A silence this long is a pause of the publisher, not lost messages.
PAUSE = 2.0
# Recent intervals the period is the median of.
WINDOW = 50


class LossCounter:
    """Counts the messages of one input missed between the stamps it saw."""

    def __init__(self):
        self.last: float | None = None
        self.intervals: deque[float] = deque(maxlen=WINDOW)
        self.period: float | None = None
        self.missed = 0
        self.logged = 0  # missed as last written to the log
        self.seen_intervals = 0

    def seen(self, stamp: float | None) -> None:
        """One message with header stamp ``stamp`` (seconds; None or 0: unstamped)."""
        if not stamp:
            return
        if self.last is None or stamp <= self.last:
            # The first one, a repeat, or a clock set back: nothing to compare.
            self.last = stamp if self.last is None or stamp < self.last - PAUSE else self.last
            return
        gap, self.last = stamp - self.last, stamp
        if gap > PAUSE:
            return
        if self.period is not None and gap > LATE * self.period:
            self.missed += round(gap / self.period) - 1
            return
        self.intervals.append(gap)
        self.seen_intervals += 1
        # The median is cheap but a 1 kHz input need not pay it for every message.
        if self.period is None and self.seen_intervals >= 5 or self.seen_intervals % 10 == 0:
            self.period = statistics.median(self.intervals)

    def report(self) -> dict:
        """What the heartbeat says about this input."""
        rate = round(1 / self.period, 1) if self.period else None
        return {"missed": self.missed, "rate": rate}
