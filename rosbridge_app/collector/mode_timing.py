"""When the robot switched: the start time of a segment from its mode message.

The collector may be starved by the robot's own work, so the time a mode
message is received can be seconds after the switch.  The message's header
stamp is the robot's own time of the switch; a message without a header still
carries the time its publisher sent it (the DDS source timestamp), and the
switch happened between the previous message (still the old mode) and this
one: that interval is the start's uncertainty, stored with the segment.
This is the rule for every mode input: the mode topic and each mode source
(whose stamp is the field its ``stamp`` names, else its ``header.stamp``).
Free of ROS.
"""

from datetime import UTC, datetime, timedelta

# A stamp further ahead of the receive time than this comes from another clock.
MAX_AHEAD = timedelta(seconds=1)
# ... and one older than this is not believed either (a robot clock that was
# never set); the receive time is taken and the uncertainty is unknown.
MAX_DELAY = timedelta(seconds=60)


def sent_at(info) -> datetime | None:
    """The publisher's send time from rmw's message info; None where the
    middleware does not give it."""
    ns = info.get("source_timestamp") if isinstance(info, dict) else None
    return datetime.fromtimestamp(ns / 1e9, tz=UTC) if ns else None


HEADER_STAMP = ("header", "stamp")


def stamp_of(msg, path: tuple = HEADER_STAMP) -> datetime | None:
    """The time at ``path`` in a message (a builtin_interfaces/Time); None
    where the message has no such field or it is unset."""
    # Imported here: conversions loads models, mode sources are also checked before.
    from rosbridge_app.collector.conversions import stamp_to_datetime

    value = msg
    try:
        for step in path:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        return stamp_to_datetime(value)
    except (AttributeError, IndexError, TypeError):
        return None


def plausible(stamp: datetime | None, at: datetime) -> bool:
    return stamp is not None and at - MAX_DELAY <= stamp <= at + MAX_AHEAD


class ModeClock:
    """Places each mode message in time; remembers the previous one."""

    def __init__(self):
        self.last_key: datetime | None = None
        self.last_sent: datetime | None = None
        self.last_mode: str | None = None
        self.heard = False

    def place(
        self, mode: str | None, stamp: datetime | None, sent: datetime | None, at: datetime
    ) -> tuple[datetime, datetime | None, float | None] | None:
        """(start, robot stamp, start uncertainty in seconds or None if unknown)
        of a message saying ``mode`` (None: a mode source's value that says
        nothing), received at ``at``; None for a copy of a message already
        placed (the latched subscription) or an older one."""
        key = stamp or sent
        if key is not None and self.last_key is not None:
            # A robot clock set back by more than MAX_DELAY starts afresh; a
            # stamp that stood still while the value changed is news.
            copy = key == self.last_key and mode == self.last_mode
            if copy or self.last_key - MAX_DELAY < key < self.last_key:
                return None
        heard, previous_sent, previous_mode = self.heard, self.last_sent, self.last_mode
        self.heard, self.last_key, self.last_sent, self.last_mode = True, key, sent, mode
        if plausible(stamp, at):
            return stamp, stamp, 0.0
        if plausible(sent, at):
            bound = None
            if heard and previous_mode != mode and previous_sent is not None:
                bound = round(max((sent - previous_sent).total_seconds(), 0.0), 3)
            return sent, sent, bound
        return at, None, None
