"""Robot mode messages and the mode publisher's rule, free of ROS."""

# The segment type keys of events.models.SegmentType, without importing Django models.
AUTO = "auto"
ITO = "ito"
# A segment logged before the robot said its mode (collector/unknown_mode.py).
UNKNOWN = "unknown"

BOOL = "bool"
INDUSTRIAL = "industrial"
MODE_TYPES = (BOOL, INDUSTRIAL)
# industrial_msgs/RobotMode
INDUSTRIAL_MANUAL = 1
INDUSTRIAL_AUTO = 2


def mode_of(msg, mode_type: str) -> str | None:
    """'auto', 'ito' or None for a value that says nothing (UNKNOWN, garbage)."""
    if mode_type == BOOL:
        return AUTO if bool(msg.data) else ITO
    value = int(msg.val)
    if value == INDUSTRIAL_AUTO:
        return AUTO
    if value == INDUSTRIAL_MANUAL:
        return ITO
    return None


def message_type(mode_type: str):
    if mode_type == BOOL:
        from std_msgs.msg import Bool

        return Bool
    from industrial_msgs.msg import RobotMode

    return RobotMode


def make_message(mode_type: str, mode: str):
    cls = message_type(mode_type)
    if mode_type == BOOL:
        return cls(data=mode == AUTO)
    return cls(val=INDUSTRIAL_AUTO if mode == AUTO else INDUSTRIAL_MANUAL)


def is_moving(twist) -> bool:
    return any(
        abs(v) > 1e-9
        for v in (
            twist.linear.x,
            twist.linear.y,
            twist.linear.z,
            twist.angular.x,
            twist.angular.y,
            twist.angular.z,
        )
    )


class ModeDecider:
    """The robotModePublisher rule: a non-zero joystick command means manual at
    once; back to auto only when navigation commands arrive and the last
    joystick command is at least ``timeout`` seconds old (the original timed it
    from the first joystick command, so it flipped back while the operator was
    still driving)."""

    def __init__(self, timeout: float = 0.5):
        self.timeout = timeout
        self.mode: str | None = None
        self.last_joystick: float | None = None

    def joystick(self, moving: bool, now: float) -> str | None:
        if moving:
            self.last_joystick = now
            self.mode = ITO
        return self.mode

    def navigation(self, now: float) -> str | None:
        if self.last_joystick is None or now - self.last_joystick >= self.timeout:
            self.mode = AUTO
        return self.mode
