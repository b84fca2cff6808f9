"""What the collector keeps while logging before the robot's mode is known.

A robot may publish its mode only on change, without a latched topic, or its
first mode message may be seconds late.  The rule, for the live collector and
the bag importer alike (both through the pipeline):

* positions (GPS fixes and local poses) that arrive while logging into an open
  leg before any mode is known are held, thinned as usual;
* if the mode becomes known within ``params.unknown_mode_wait`` seconds of the
  first held position, the first master starts at that position and takes
  every held position;
* if the wait passes first, or logging or the collector (SIGINT, SIGTERM)
  stops before a mode is known, a master of *unknown* mode opens at the first
  held position, takes the held positions and records later ones as they come;
  the first known mode closes it like any switch. A hard kill (SIGKILL, power)
  loses what is held: at most the wait.

The statistics count unknown masters as time and distance without a known
mode (reports/selectors/statistics.py). Free of ROS.
"""

from collections import deque
from datetime import datetime

# Thinned positions of each kind kept while waiting (hours at the default thinning).
MAX_HELD = 50_000


class ModeWait:
    """Positions held until the mode is known or the wait is over."""

    def __init__(self):
        self.fixes: deque[tuple[datetime, dict]] = deque(maxlen=MAX_HELD)
        self.poses: deque[tuple[datetime, dict]] = deque(maxlen=MAX_HELD)

    def __bool__(self) -> bool:
        return bool(self.fixes or self.poses)

    def first_at(self) -> datetime | None:
        firsts = [held[0][0] for held in (self.fixes, self.poses) if held]
        return min(firsts) if firsts else None

    def is_over(self, at: datetime, wait: float) -> bool:
        """True once ``wait`` seconds have passed since the first held position."""
        first = self.first_at()
        return first is not None and (at - first).total_seconds() >= wait

    def take(self) -> tuple[list[tuple[datetime, dict]], list[tuple[datetime, dict]]]:
        """The held fixes and poses, oldest first; nothing is held afterwards."""
        fixes, poses = list(self.fixes), list(self.poses)
        self.clear()
        return fixes, poses

    def clear(self) -> None:
        self.fixes.clear()
        self.poses.clear()
