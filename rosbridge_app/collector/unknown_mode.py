"""What the collector keeps while logging before the robot's mode is known.

A robot may publish its mode only on change, without a latched topic, or its
first mode message may be seconds late.  The rule, for the live collector and
the bag importer alike (both through the pipeline):

* positions (GPS fixes and local poses) that arrive while logging into an open
  leg before any mode is known are held, thinned as usual;
* the first mode heard says what the held positions were, and the first
  master starts at the first held position and takes them all, when

  - it was sent at or before the first held position (a latched sample: a
    transient-local publisher gives a late joiner its last message with the
    time it was sent; or one delivered late), or
  - no mode publisher was connected when the first position was held (the
    robot's mode node started later; a recording does not say when its
    recorder joined the mode topic), and it came within
    ``params.unknown_mode_wait`` seconds of the first held position, or
  - its publisher repeats it (periodic): the same mode is heard again within
    the wait, no sooner than half the time the first message came after the
    first held position, so the held positions lie within two periods before
    it;

* otherwise it is a switch (an on-change publisher the collector was already
  connected to said nothing while the robot drove): the held positions before
  its time go to a master of *unknown* mode, the switch keeps its own time,
  and the reason rules are asked at that time.  It is stored once it cannot
  prove periodic any more: another mode, a repeat too soon, the wait passed
  since it came, or logging stopping;
* if the wait passes with no mode at all, or logging or the collector
  (SIGINT, SIGTERM) stops before a mode is known, a master of unknown mode
  opens at the first held position, takes the held positions and records
  later ones as they come; the first known mode closes it like any switch.
  A hard kill (SIGKILL, power) loses what is held: at most the wait.

The statistics count unknown masters as time and distance without a known
mode (reports/selectors/statistics.py). Free of ROS.
"""

from collections import deque
from datetime import datetime, timedelta
from typing import NamedTuple

# Thinned positions of each kind kept while waiting (hours at the default thinning).
MAX_HELD = 50_000


class FirstMode(NamedTuple):
    """The first mode heard while positions are held, not yet known to say what
    they were: when it was said (``at``, robot time), when it was received, the
    timing of its switch and the reason the rules suggested then."""

    mode: str
    at: datetime
    received: datetime
    robot_stamp: datetime | None
    uncertainty: float | None
    reason: str | None


class ModeWait:
    """Positions held until the mode is known or the wait is over."""

    def __init__(self):
        self.fixes: deque[tuple[datetime, dict]] = deque(maxlen=MAX_HELD)
        self.poses: deque[tuple[datetime, dict]] = deque(maxlen=MAX_HELD)
        # Whether a mode publisher was connected when the first position was held.
        self.listening = False
        self.first_mode: FirstMode | None = None

    def __bool__(self) -> bool:
        return bool(self.fixes or self.poses)

    def first_at(self) -> datetime | None:
        firsts = [held[0][0] for held in (self.fixes, self.poses) if held]
        return min(firsts) if firsts else None

    def is_over(self, at: datetime, wait: float) -> bool:
        """True once ``wait`` seconds have passed since the first held position."""
        first = self.first_at()
        return first is not None and (at - first).total_seconds() >= wait

    def says_what_was_held(self, at: datetime, first: datetime) -> bool:
        """Whether a first mode said at ``at``, heard within the wait, covers
        the held positions without repeating itself; ``first``: the first held
        position's time on the same clock (the robot's)."""
        return at <= first or not self.listening

    def repeats(self, received: datetime) -> bool | None:
        """The pending first mode heard again at ``received``: True if it is
        periodic enough to cover the held positions, False if not; None when
        no first mode is pending."""
        pending = self.first_mode
        if pending is None:
            return None
        # Its first message may come up to a period late (a busy robot, or the
        # mode topic matched after the positions' topic): two periods, not one.
        return 2 * (received - pending.received) >= pending.received - self.first_at()

    def undecided_until(self, wait: float) -> datetime | None:
        """After this time the pending first mode can no longer prove periodic."""
        pending = self.first_mode
        return None if pending is None else pending.received + timedelta(seconds=wait)

    def take(self) -> tuple[list[tuple[datetime, dict]], list[tuple[datetime, dict]]]:
        """The held fixes and poses, oldest first; nothing is held afterwards."""
        fixes, poses = list(self.fixes), list(self.poses)
        self.clear()
        return fixes, poses

    def clear(self) -> None:
        self.fixes.clear()
        self.poses.clear()
        self.listening = False
        self.first_mode = None
