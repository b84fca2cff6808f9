"""Messages lost on the way, told from gaps the publisher left.  Free of ROS.

Two figures per input, under their own names:

* **dropped**: messages the publisher sent that the collector never handled
  (lost in DDS, or overwritten in the subscription's queue while the
  collector was starved).  Each DDS message carries its publisher's sequence
  number (rmw's ``publication_sequence_number``, which does not name the
  publisher); a jump by k means k - 1 sent messages were dropped.  A number
  is taken to follow the nearest lower one heard last (several publishers
  of one topic, up to PUBLISHERS, each keep their own count); a number below
  all of them is a new or restarted publisher.  Interleaved publishers with
  close numbers may hide a drop, never invent one beyond the true jumps.
* **publisher gaps**: messages the publisher did not send at its own rate (a
  loaded robot whose timer fired late): nothing was lost.  A topic published
  at a steady rate whose stamps jump by k periods lacks k - 1 messages there;
  those the sequence numbers say were dropped are not gaps.  The period is
  measured, not configured: the mean of the recent ordinary intervals, so a
  loaded robot's timer, late once and early the next time, averages out.  An
  interval counts only beyond LATE times the median interval, so such jitter
  is neither.  A silence longer than PAUSE is the robot not publishing (no
  fix, a paused bag).  Without sequence numbers (a middleware that has none)
  stamp gaps cannot be told from drops; they are counted as publisher gaps.
"""

import statistics
from collections import deque

# An interval this many times the median holds missing messages.
LATE = 1.5
# A silence this long is a pause of the publisher, not missing messages.
PAUSE = 2.0
# Recent intervals the rate is measured over.
WINDOW = 50
# Intervals needed before gaps are judged.
FIRST = 5
# Publishers of one topic whose sequence numbers are followed at once.
PUBLISHERS = 4


class LossCounter:
    """Counts the messages of one input dropped, and those its publisher left out."""

    def __init__(self):
        self.last: float | None = None
        # The last sequence number of each publisher heard recently.
        self.sequences: deque[int] = deque(maxlen=PUBLISHERS)
        self.intervals: deque[float] = deque(maxlen=WINDOW)
        self.median: float | None = None
        self.period: float | None = None
        self.total = 0.0  # of the intervals
        self.taken = 0
        self.dropped = 0
        self.gaps = 0
        self.logged = 0  # dropped as last written to the log
        self.logged_gaps = 0

    def seen(self, stamp: float | None, sequence: int | None = None) -> None:
        """One message with header stamp ``stamp`` (seconds; None or 0:
        unstamped) and its publisher's sequence number (None: unknown)."""
        dropped = self._count_dropped(sequence)
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
            self.gaps += max(0, round(gap / self.period) - 1 - dropped)
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

    def _count_dropped(self, sequence: int | None) -> int:
        if sequence is None:
            return 0
        # The publisher whose last number is the nearest below this one sent it.
        below = [last for last in self.sequences if last < sequence]
        if not below:
            self.sequences.append(sequence)  # a new or restarted publisher
            return 0
        last = max(below)
        self.sequences.remove(last)
        self.sequences.append(sequence)
        self.dropped += sequence - last - 1
        return sequence - last - 1

    def report(self) -> dict:
        """What the heartbeat says about this input."""
        rate = round(1 / self.period, 1) if self.period else None
        return {"dropped": self.dropped, "publisher_gaps": self.gaps, "rate": rate}
