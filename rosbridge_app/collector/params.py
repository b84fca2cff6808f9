"""The collector's ROS parameters: names, defaults, checks, and the YAML file.

Names follow the original node (``topics.*``, ``params.*`` and the three
service names); everything this project adds is listed in docs/collector.md.
The file format is the standard ROS 2 parameters file, so it can be passed to
``--params-file`` of any ROS tool as well.
"""

import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import yaml
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from common.numbers import short
from rosbridge_app.collector import mode_sources, reason_rules
from rosbridge_app.collector.message_fields import installed_fields
from rosbridge_app.collector.modes import MODE_TYPES

NODE_NAME = "ftt_collector"
# Characters a text parameter may have: some hundred mode sources or reason
# rules; one change is checked, stored and applied under the write lock.
MAX_TEXT = 20_000
NAV_SAT_FIX = "sensor_msgs/msg/NavSatFix"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
# The mode topic's message type for each params.robot_mode_type.
ROBOT_MODE_TYPES = {
    "bool": ("std_msgs/msg/Bool",),
    "industrial": ("industrial_msgs/msg/RobotMode",),
}
DEFAULT_FILE = Path(__file__).resolve().parent.parent / "config" / "ftt_collect.yaml"


@dataclass(frozen=True)
class Spec:
    """One parameter: the collector declares it, the web side checks and edits
    it, the bag importer reads it; all from this table."""

    default: object
    description: str
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple | None = None
    topic: bool = False
    # Message types a topic parameter takes, so the editor suggests only those.
    message_types: tuple[str, ...] = ()
    # A YAML document: the editor gives it a text area.
    multiline: bool = False

    @property
    def kind(self) -> str:
        """bool, int, float or str: the type the value must have."""
        for kind in (bool, int, float):
            if isinstance(self.default, kind):
                return kind.__name__
        return "str"


SPECS: dict[str, Spec] = {
    "vehicle": Spec(
        "", gettext_noop("Vehicle key; the collector logs into its open shift's open leg.")
    ),
    "set_ftt_logging_service": Spec(
        "/set_ftt_logging", gettext_noop("SetBool: start/stop logging.")
    ),
    "get_ftt_logging_service": Spec(
        "/get_ftt_logging", gettext_noop("Trigger: success = logging.")
    ),
    "save_ftt_params_service": Spec(
        "/save_ftt_params", gettext_noop("Trigger: write parameters to file.")
    ),
    "snapshot_ftt_service": Spec(
        "/ftt_snapshot", gettext_noop("Trigger: write a black-box snapshot now.")
    ),
    # Its message type follows params.robot_mode_type (see ROBOT_MODE_TYPES).
    "topics.robot_mode": Spec("robot_mode", gettext_noop("Operating mode topic."), topic=True),
    "topics.gps_fix": Spec(
        "gps_fix",
        gettext_noop("sensor_msgs/NavSatFix topic."),
        topic=True,
        message_types=(NAV_SAT_FIX,),
    ),
    "topics.local_pose": Spec(
        "local_pose",
        gettext_noop("geometry_msgs/PoseStamped (use_tf false)."),
        topic=True,
        message_types=("geometry_msgs/msg/PoseStamped",),
    ),
    "topics.map": Spec(
        "map",
        gettext_noop("nav_msgs/OccupancyGrid topic."),
        topic=True,
        message_types=("nav_msgs/msg/OccupancyGrid",),
    ),
    "topics.map_jpeg": Spec(
        "",
        gettext_noop("sensor_msgs/CompressedImage of the same map; empty: off."),
        topic=True,
        message_types=(COMPRESSED_IMAGE,),
    ),
    "topics.image": Spec(
        "image",
        gettext_noop("sensor_msgs/Image camera topic; empty: off."),
        topic=True,
        message_types=("sensor_msgs/msg/Image",),
    ),
    "topics.image_compressed": Spec(
        "",
        gettext_noop("sensor_msgs/CompressedImage camera; empty: off."),
        topic=True,
        message_types=(COMPRESSED_IMAGE,),
    ),
    "topics.tf": Spec(
        "/tf", gettext_noop("Dynamic transforms."), topic=True, message_types=(TF_MESSAGE,)
    ),
    "topics.tf_static": Spec(
        "/tf_static", gettext_noop("Static transforms."), topic=True, message_types=(TF_MESSAGE,)
    ),
    "params.robot_mode_type": Spec(
        "bool",
        gettext_noop(
            "bool (std_msgs/Bool, true = autonomous) or industrial (industrial_msgs/RobotMode)."
        ),
        choices=MODE_TYPES,
    ),
    "params.mode_sources": Spec(
        "",
        gettext_noop(
            "Mode from any topics (YAML: rule, sources with topic, type, field, auto, ito, "
            "default, hysteresis, stamp; presets: manage.py ftt_mode_presets); empty: "
            "topics.robot_mode with params.robot_mode_type."
        ),
        multiline=True,
    ),
    "params.reason_rules": Spec(
        "",
        gettext_noop(
            "Reasons the robot knows (YAML: window, rules with topic, type, field and values, "
            "or silent, and reason); the take-over gets the reason as a suggestion to confirm."
        ),
        multiline=True,
    ),
    "params.use_tf": Spec(
        True, gettext_noop("Local position from TF map_frame→robot_frame, else local_pose.")
    ),
    "params.map_frame": Spec("map", gettext_noop("Frame of local positions.")),
    "params.robot_frame": Spec("base_link", gettext_noop("The robot's frame.")),
    "params.sensor_reliable": Spec(
        False,
        gettext_noop(
            "Subscribe GPS/pose/camera RELIABLE; the default "
            "BEST_EFFORT connects to publishers of either kind."
        ),
    ),
    "params.pose_min_distance": Spec(
        0.5, gettext_noop("GPS: metres between recorded fixes."), minimum=0.0
    ),
    "params.pose_min_period": Spec(
        0.2, gettext_noop("GPS: seconds between recorded fixes."), minimum=0.0
    ),
    "params.local_min_distance": Spec(
        0.2, gettext_noop("Local: metres between recorded poses."), minimum=0.0
    ),
    "params.local_min_period": Spec(
        0.1, gettext_noop("Local: seconds between recorded poses."), minimum=0.0
    ),
    "params.local_min_yaw": Spec(
        0.1, gettext_noop("Local: a turn of this many radians is recorded too."), minimum=0.0
    ),
    "params.position_max_age": Spec(
        5.0,
        gettext_noop("A segment's start position is the last one if it is at most this old (s)."),
        minimum=0.0,
    ),
    "params.unknown_mode_wait": Spec(
        10.0,
        gettext_noop(
            "Seconds to wait for the robot's first mode after logging starts, and for it to "
            "repeat; positions meanwhile join the first segment if that mode was latched or "
            "periodic, else and after the wait they go to a segment of unknown mode (s)."
        ),
        minimum=0.0,
    ),
    "params.deaf_timeout": Spec(
        5.0,
        gettext_noop(
            "Seconds with nothing received on any input while other nodes publish the "
            "collector's sensor topics (GPS, TF, local pose, camera), before the collector "
            "re-creates its subscriptions, and if that does not help, itself; 0: off."
        ),
        minimum=0.0,
        maximum=3600.0,
    ),
    "params.send_map_period": Spec(
        2.0, gettext_noop("Minimum seconds between two stored maps."), minimum=0.0
    ),
    "params.image_buffer_size": Spec(
        3, gettext_noop("Camera frames kept for the next mode switch."), minimum=0, maximum=20
    ),
    "params.image_buffer_step": Spec(
        1.0, gettext_noop("Minimum seconds between buffered frames."), minimum=0.0
    ),
    "params.image_max_side": Spec(
        1920,
        gettext_noop("Larger frames are scaled down to this (px); 0: never."),
        minimum=0,
        maximum=16384,
    ),
    "snapshot.enabled": Spec(
        True,
        gettext_noop(
            "Black box: write an MCAP snapshot of the last seconds at every switch to ITO."
        ),
    ),
    "snapshot.topics": Spec(
        "",
        gettext_noop(
            "Comma-separated topics of any type for snapshots; empty: the mode, GPS, TF, "
            "static TF and compressed camera topics above, plus odom and cmd_vel when published."
        ),
    ),
    "snapshot.before": Spec(
        20.0, gettext_noop("Snapshot: seconds before the trigger."), minimum=0.0, maximum=600.0
    ),
    "snapshot.after": Spec(
        10.0, gettext_noop("Snapshot: seconds after the trigger."), minimum=0.0, maximum=600.0
    ),
    "snapshot.buffer_mb": Spec(
        200,
        gettext_noop("Snapshot buffer size (MB); the oldest messages go first."),
        minimum=1,
        maximum=8192,
    ),
    "snapshot.disk_budget_mb": Spec(
        2000,
        gettext_noop(
            "Disk for snapshots not yet stored (MB); when full the oldest pending one is dropped."
        ),
        minimum=1,
        maximum=1_000_000,
    ),
    "snapshot.write_timeout": Spec(
        60.0,
        gettext_noop(
            "Seconds a snapshot file may take to write, plus 1 s per MB of its window; a "
            "writer process not done by then is taken as stuck: killed, logged and replaced."
        ),
        minimum=1.0,
        maximum=3600.0,
    ),
    "spool.disk_budget_mb": Spec(
        4000,
        gettext_noop(
            "Disk for everything the collector writes: spool, snapshots, pending files (MB); "
            "near it snapshots are dropped, at it records are held in memory; camera frames "
            "dropped and positions thinned while the database does not answer "
            "(docs/collector.md, 'A full disk')."
        ),
        minimum=1,
        maximum=1_000_000,
    ),
    "spool.disk_headroom_mb": Spec(
        100,
        gettext_noop("Disk left free for the rest of the robot (MB); counts like the budget."),
        minimum=0,
        maximum=1_000_000,
    ),
}


class InvalidParameter(ValueError):
    pass


def check(name: str, value, fields_of=installed_fields) -> object:
    """The value to keep, or InvalidParameter with a reason a person understands."""
    spec = SPECS.get(name)
    if spec is None:
        return value
    return _checked(name, spec, value, fields_of)


def expected_types(name: str, values: dict) -> tuple[str, ...]:
    """Message types topic parameter ``name`` takes, given the other values."""
    if name == "topics.robot_mode":
        mode_type = values.get("params.robot_mode_type", SPECS["params.robot_mode_type"].default)
        return ROBOT_MODE_TYPES.get(mode_type, ())
    spec = SPECS.get(name)
    return spec.message_types if spec else ()


def _checked(name: str, spec: Spec, value, fields_of=installed_fields) -> object:
    default = spec.default
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise InvalidParameter(_("%(name)s must be true or false") % {"name": name})
    elif isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise InvalidParameter(_("%(name)s must be an integer") % {"name": name})
    elif isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InvalidParameter(_("%(name)s must be a number") % {"name": name})
        value = float(value)
        if not math.isfinite(value):
            raise InvalidParameter(_("%(name)s must be finite") % {"name": name})
    elif isinstance(default, str) and not isinstance(value, str):
        raise InvalidParameter(_("%(name)s must be a string") % {"name": name})
    if isinstance(value, str) and len(value) > MAX_TEXT:
        raise InvalidParameter(
            _("%(name)s is longer than %(limit)s characters") % {"name": name, "limit": MAX_TEXT}
        )
    if spec.minimum is not None and value < spec.minimum:
        raise InvalidParameter(
            _("%(name)s must be >= %(limit)s") % {"name": name, "limit": short(spec.minimum)}
        )
    if spec.maximum is not None and value > spec.maximum:
        raise InvalidParameter(
            _("%(name)s must be <= %(limit)s") % {"name": name, "limit": short(spec.maximum)}
        )
    if spec.choices is not None and value not in spec.choices:
        raise InvalidParameter(
            _("%(name)s must be one of %(choices)s")
            % {"name": name, "choices": ", ".join(spec.choices)}
        )
    if name in DOCUMENTS:
        parse = mode_sources.parse if name == "params.mode_sources" else reason_rules.parse
        try:
            parse(value, fields_of)
        except mode_sources.InvalidModeSources as exc:
            raise InvalidParameter(f"{name}: {exc}") from None
    if name.endswith("_service") and not value:
        raise InvalidParameter(_("%(name)s cannot be empty") % {"name": name})
    return value


def _nested(flat: dict) -> dict:
    tree: dict = {}
    for name, value in sorted(flat.items()):
        node = tree
        *parents, leaf = name.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return tree


# Parameters holding a YAML document; a parameters file may write them as
# nested YAML (the presets' shape) or as text.
DOCUMENTS = ("params.mode_sources", "params.reason_rules")


def _flatten(tree: dict, prefix: str = "") -> dict:
    flat = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if name in DOCUMENTS and isinstance(value, dict | list):
            flat[name] = yaml.safe_dump(value, sort_keys=False)
        elif isinstance(value, dict):
            flat.update(_flatten(value, name + "."))
        else:
            flat[name] = value
    return flat


def read_file(path: Path, node_name: str = NODE_NAME) -> dict:
    """Flat {name: value} of the node's section (or the ``/**`` wildcard section)."""
    data = yaml.safe_load(Path(path).read_text()) or {}
    for key in (node_name, f"/{node_name}", "/**"):
        section = data.get(key)
        if isinstance(section, dict) and isinstance(section.get("ros__parameters"), dict):
            return _flatten(section["ros__parameters"])
    return {}


def written_documents(path: Path) -> dict:
    """{name: text} of the YAML-document parameters a parameters file sets:
    rcl reads a nested mapping there as other parameters' names, so the
    collector takes these values from the file itself."""
    return {name: v for name, v in read_file(path).items() if name in DOCUMENTS}


class _Dumper(yaml.SafeDumper):
    """Text of several lines as a literal block, so a saved YAML document stays
    hand-editable (rcl reads it as the same string)."""


def _text(dumper, value: str):
    style = "|" if "\n" in value else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)


_Dumper.add_representer(str, _text)


def write_file(path: Path, values: dict, node_name: str = NODE_NAME) -> None:
    """Write the node's section, keeping other nodes' sections of the same file.

    Written to a temporary file and renamed, so a crash never leaves half a file.
    """
    path = Path(path)
    data = {}
    if path.exists():
        data = yaml.safe_load(path.read_text()) or {}
        if not isinstance(data, dict):
            data = {}
    for key in (f"/{node_name}", "/**"):
        if key in data and isinstance(data[key], dict) and "ros__parameters" in data[key]:
            node_key = key
            break
    else:
        node_key = node_name
    data[node_key] = {"ros__parameters": _nested(values)}
    text = (
        "# ftt_collect parameters (ROS 2 parameters file). Written by /save_ftt_params;\n"
        "# see docs/collector.md for what each one does.\n"
        + yaml.dump(data, Dumper=_Dumper, sort_keys=False, default_flow_style=False)
    )
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
