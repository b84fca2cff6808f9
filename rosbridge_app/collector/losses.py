"""Messages lost on the way, estimated from the robot's stamps.  Free of ROS.

A topic published at a steady rate whose stamps jump by k periods lost
k - 1 messages there (in DDS, in a full history while the collector was
starved, or on the robot).  The period is measured, not configured: the mean
of the recent ordinary intervals, so a loaded robot's timer, late once and
early the next time, averages out.  An interval counts as a gap only beyond
LATE times the median interval, so such jitter is no loss either.  A silence
longer than PAUSE is the robot not publishing (no fix, a paused bag).
"""

import statistics
from collections import deque

# An interval this many times the median holds missed messages.
LATE = 1.5
# A silence this long is a pause of the publisher, not lost messages.
PAUSE = 2.0
# Recent intervals the rate is measured over.
WINDOW = 50
# Intervals needed before gaps are judged.
FIRST = 5


class LossCounter:
    """Counts the messages of one input missed between the stamps it saw."""

    def __init__(self):
        self.last: float | None = None
        self.intervals: deque[float] = deque(maxlen=WINDOW)
        self.median: float | None = None
        self.period: float | None = None
        self.total = 0.0  # of the intervals
        self.taken = 0
        self.missed = 0
        self.logged = 0  # missed as last written to the log

    def seen(self, stamp: float | None) -> None:
        """One message with header stamp ``stamp`` (seconds; None or 0: unstamped)."""
        if not stamp:
            return
        if self.last is not None and stamp <= self.last:
            if stamp < self.last - PAUSE:  # a clock set back
                self.last = stamp
            return  # a repeat or one out of order
        gap = None if self.last is None else stamp - self.last
        self.last = stamp
        if gap is None or gap > PAUSE:
            return
        if self.median is not None and gap > LATE * self.median:
            self.missed += max(0, round(gap / self.period) - 1)
            return
        if len(self.intervals) == WINDOW:
            self.total -= self.intervals[0]
        self.intervals.append(gap)
        self.total += gap
        self.taken += 1
        if len(self.intervals) >= FIRST:
            self.period = self.total / len(self.intervals)
            # The median is cheap but a 1 kHz input need not pay it for every message.
            if self.median is None or self.taken % 10 == 0:
                self.median = statistics.median(self.intervals)

    def report(self) -> dict:
        """What the heartbeat says about this input."""
        rate = round(1 / self.period, 1) if self.period else None
        return {"missed": self.missed, "rate": rate}
