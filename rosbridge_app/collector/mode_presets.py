"""Mode-source presets: named ``params.mode_sources`` documents for robots
that publish a known message type.

The one home of the presets: ``manage.py ftt_mode_presets`` lists and prints
them, and docs/collector.md shows them as printed (a test holds the two
together). Each document goes through the same check as the parameter.

Where several fields of one message are sources, the vetoes come first: each
source's value is combined as it is offered, in the listed order, so a mode
field listed before its veto would open an AUTO segment of no length.
"""

from dataclasses import dataclass

from django.utils.translation import gettext_lazy as _


@dataclass(frozen=True)
class Preset:
    name: str
    summary: str  # one line, translated where shown
    document: str  # YAML, ready to paste as params.mode_sources


PRESETS = (
    Preset(
        "bool",
        _("std_msgs/Bool, true = autonomous (what params.robot_mode_type: bool does)"),
        """\
sources:
  - {topic: robot_mode, type: std_msgs/msg/Bool, field: data, auto: [true], ito: [false]}
""",
    ),
    Preset(
        "string",
        _("std_msgs/String (or a string field of the team's own state message): AUTO, else ITO"),
        """\
sources:
  - {topic: /robot/mode, type: std_msgs/msg/String, field: data, auto: [AUTO], default: ito}
""",
    ),
    Preset(
        "industrial",
        _("industrial_msgs/RobotMode (what params.robot_mode_type: industrial does)"),
        """\
sources:
  - {topic: robot_mode, type: industrial_msgs/msg/RobotMode, field: val, auto: [2], ito: [1]}
""",
    ),
    Preset(
        "mavros",
        _(
            "MAVROS mavros_msgs/State of a PX4 flight controller; disarmed is ITO "
            "(build mavros_msgs)"
        ),
        """\
rule: any_ito
sources:
  - {topic: /mavros/state, type: mavros_msgs/msg/State, field: armed, ito: [false]}
  - {topic: /mavros/state, type: mavros_msgs/msg/State, field: mode,
     auto: [OFFBOARD, AUTO.MISSION, AUTO.LOITER, AUTO.RTL, AUTO.LAND, AUTO.TAKEOFF,
            AUTO.PRECLAND, AUTO.FOLLOW_TARGET, AUTO.RTGS],
     ito: [MANUAL, ACRO, ALTCTL, POSCTL, STABILIZED, RATTITUDE]}
""",
    ),
    Preset(
        "autoware",
        _(
            "Autoware OperationModeState (autoware_adapi_v1_msgs): AUTONOMOUS is AUTO once its "
            "transition ends; a driver override is ITO (build autoware_adapi_v1_msgs)"
        ),
        """\
rule: any_ito
sources:
  - {topic: /api/operation_mode/state, type: autoware_adapi_v1_msgs/msg/OperationModeState,
     field: is_in_transition, stamp: stamp, ito: [true]}
  - {topic: /api/operation_mode/state, type: autoware_adapi_v1_msgs/msg/OperationModeState,
     field: is_autoware_control_enabled, stamp: stamp, ito: [false]}
  - {topic: /api/operation_mode/state, type: autoware_adapi_v1_msgs/msg/OperationModeState,
     field: mode, stamp: stamp, auto: [2], ito: [1, 3, 4]}
""",
    ),
    Preset(
        "deadman",
        _("a joystick dead-man button (sensor_msgs/Joy), vetoed by a safety controller's e-stop"),
        """\
rule: any_ito
sources:
  - {topic: /joy, type: sensor_msgs/msg/Joy, field: "buttons[4]", ito: [1], auto: [0],
     hysteresis: 0.3}
  - {topic: /estop, type: std_msgs/msg/Bool, field: data, ito: [true]}
""",
    ),
)


def preset(name: str) -> Preset:
    """The preset called ``name``; KeyError if there is none."""
    for candidate in PRESETS:
        if candidate.name == name:
            return candidate
    raise KeyError(name)
