"""When the GUI may start or stop logging (the seeds' rule, kept in one place).

Starting needs an online collector and an open test event, shift and leg;
stopping is always allowed while the collector logs, even when the levels
were closed elsewhere in the meantime.
"""

from events.errors import RuleViolation
from events.models import Leg
from rosbridge_app.models import Collector
from rosbridge_app.selectors.collectors import is_online


def logging_control(collector: Collector | None, leg: Leg | None) -> tuple[bool, str]:
    """(may the button be pressed, why not / what it does) for the selected leg."""
    if collector is None:
        return False, "No collector has reported for this vehicle."
    if collector.logging:
        return True, "Stopping ends the open segment."
    if not is_online(collector):
        return False, "The collector is offline."
    if leg is None:
        return False, "Select a test event, shift and leg."
    shift = leg.shift
    if not (leg.is_open and shift.is_open and shift.test_event.is_open):
        return False, "Logging needs an open test event, shift and leg."
    if shift.vehicle_id != collector.vehicle_id:
        return False, "This collector belongs to another vehicle."
    return True, ""


# Message type each topic parameter expects, so the editor can suggest only
# topics of that type from the robot's graph.
TOPIC_TYPES = {
    "topics.gps_fix": ("sensor_msgs/msg/NavSatFix",),
    "topics.local_pose": ("geometry_msgs/msg/PoseStamped",),
    "topics.map": ("nav_msgs/msg/OccupancyGrid",),
    "topics.map_jpeg": ("sensor_msgs/msg/CompressedImage",),
    "topics.image": ("sensor_msgs/msg/Image",),
    "topics.image_compressed": ("sensor_msgs/msg/CompressedImage",),
    "topics.tf": ("tf2_msgs/msg/TFMessage",),
    "topics.tf_static": ("tf2_msgs/msg/TFMessage",),
}
ROBOT_MODE_TYPES = {
    "bool": ("std_msgs/msg/Bool",),
    "industrial": ("industrial_msgs/msg/RobotMode",),
}


def _kind(value) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    return "str"


def parameter_rows(collector: Collector) -> list[dict]:
    """The collector's parameters with their type, meaning and topic suggestions."""
    from rosbridge_app.collector.params import SPECS

    values = collector.parameters or {}
    topics = collector.topics or []
    rows = []
    for name in sorted(values):
        value = values[name]
        expected = TOPIC_TYPES.get(name)
        if name == "topics.robot_mode":
            expected = ROBOT_MODE_TYPES.get(values.get("params.robot_mode_type"), ())
        spec = SPECS.get(name)
        rows.append(
            {
                "name": name,
                "value": value,
                "type": _kind(value),
                "description": spec.description if spec else "",
                "choices": list(spec.choices) if spec and spec.choices else None,
                "expects": list(expected or ()),
                "suggestions": sorted(
                    t["name"] for t in topics if set(t.get("types", ())) & set(expected or ())
                ),
            }
        )
    return rows


def check_parameter_values(collector: Collector, changes: dict) -> dict:
    """Changed values with the type the parameter has now; refuses unknown names
    and values of another type (an int is accepted where a float is expected)."""
    current = collector.parameters or {}
    errors, checked = {}, {}
    for name, value in changes.items():
        if name not in current:
            errors[name] = ["The collector has no such parameter."]
            continue
        kind, given = _kind(current[name]), _kind(value)
        if kind == "float" and given == "int":
            value, given = float(value), "float"
        if kind != given:
            names = {
                "bool": "true or false",
                "int": "a whole number",
                "float": "a number",
                "str": "text",
            }
            errors[name] = [f"Must be {names[kind]}."]
            continue
        checked[name] = value
    if errors:
        raise RuleViolation(errors)
    return checked
