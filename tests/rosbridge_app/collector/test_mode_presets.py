"""The mode-source presets (mode_presets.py): each passes the parameter's
check against the message definitions its robots publish, and sample messages
of that type give the mode a field tester expects (no ROS)."""

import io
import re
from datetime import UTC, datetime, timedelta
from pathlib import Path
from types import SimpleNamespace as NS

import pytest
from django.core.management import CommandError, call_command
from django.utils import translation
from rosbags.typesys import Stores, get_typestore

from rosbridge_app.collector import params as P
from rosbridge_app.collector.message_fields import folder_types, recorded_fields
from rosbridge_app.collector.mode_presets import PRESETS, preset
from rosbridge_app.collector.mode_sources import Combiner, parse

T0 = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)
# Upstream's field lists of the types FTT does not install (mavros_msgs, Autoware).
UPSTREAM = Path(__file__).parent / "robot_msgs" / "upstream"


def at(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


def stamp(seconds: float) -> NS:
    t = at(seconds).timestamp()
    return NS(sec=int(t), nanosec=int(round(t % 1 * 1e9)))


def upstream_fields():
    store = get_typestore(Stores.ROS2_JAZZY)
    for package in sorted(UPSTREAM.iterdir()):
        store.register(folder_types(package))
    return recorded_fields(store)


def mavros(seconds: float, armed: bool, mode: str) -> NS:
    return NS(header=NS(stamp=stamp(seconds)), armed=armed, mode=mode)


def autoware(seconds: float, mode: int, in_transition=False, control=True) -> NS:
    return NS(
        stamp=stamp(seconds),
        mode=mode,
        is_in_transition=in_transition,
        is_autoware_control_enabled=control,
    )


# Per preset: (seconds, source, message, the combined mode after it).
SAMPLES = {
    "bool": [(0, 0, NS(data=True), "auto"), (1, 0, NS(data=False), "ito")],
    "string": [
        (0, 0, NS(data="AUTO"), "auto"),
        (1, 0, NS(data="manual"), "ito"),  # a value the list lacks is not AUTO
        (2, 0, NS(data="AUTO"), "auto"),
        (3, 0, NS(data="IDLE"), "ito"),
    ],
    "industrial": [
        (0, 0, NS(val=2), "auto"),
        (1, 0, NS(val=1), "ito"),
        (2, 0, NS(val=-1), "ito"),  # UNKNOWN says nothing
    ],
    "mavros": [
        (0, 0, mavros(0, True, "AUTO.MISSION"), "auto"),
        (1, 0, mavros(1, True, "ACRO"), "ito"),
        (2, 0, mavros(2, True, "OFFBOARD"), "auto"),
        (3, 0, mavros(3, False, "OFFBOARD"), "ito"),  # disarmed: nobody drives it
    ],
    "autoware": [
        (0, 0, autoware(0, 3), "ito"),  # LOCAL: the joystick
        (1, 0, autoware(1, 2, in_transition=True), "ito"),  # the driver is still responsible
        (2, 0, autoware(2, 2), "auto"),
        (3, 0, autoware(3, 2, control=False), "ito"),  # the driver took the wheel
        (4, 0, autoware(4, 2), "auto"),
        (5, 0, autoware(5, 1), "ito"),  # STOP
    ],
    "deadman": [
        (0, 0, NS(header=NS(stamp=stamp(0)), buttons=[0, 0, 0, 0, 0]), None),
        (0.5, 0, NS(header=NS(stamp=stamp(0.5)), buttons=[0, 0, 0, 0, 0]), "auto"),
        (1, 1, NS(data=True), "ito"),  # the e-stop vetoes
        (2, 1, NS(data=False), "auto"),
    ],
}


def test_every_preset_has_samples_and_a_name_of_its_own():
    names = [p.name for p in PRESETS]
    assert sorted(names) == sorted(SAMPLES) and len(set(names)) == len(names)
    with pytest.raises(KeyError):
        preset("no_such_robot")


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_a_preset_passes_the_parameter_check_and_maps_its_messages(name):
    document = preset(name).document
    assert P.check("params.mode_sources", document, upstream_fields()) == document
    combiner = Combiner(parse(document))
    topics = parse(document).by_topic()
    for seconds, source, msg, expected in SAMPLES[name]:
        # As the collector does: each message to every source of its topic.
        switches = []
        for index in topics[parse(document).sources[source].topic.lstrip("/")]:
            switches += combiner.offer(index, msg, at(seconds), sent=at(seconds))
        switches += combiner.tick(at(seconds))
        assert combiner.mode == expected, (seconds, msg)
        assert len(switches) <= 1, f"one message opened segments of no length: {switches}"


def test_autoware_switches_at_the_stamp_of_the_completed_transition():
    combiner = Combiner(parse(preset("autoware").document))
    switches = []
    for seconds, msg in [(0, autoware(0, 3)), (1, autoware(1, 2, True)), (2.5, autoware(2.5, 2))]:
        for index in range(3):  # received 0.4 s after the robot's stamp
            switches += combiner.offer(index, msg, at(seconds + 0.4), sent=at(seconds + 0.3))
    assert [(s.mode, s.at, s.uncertainty) for s in switches] == [
        ("ito", at(0), 0.0),
        ("auto", at(2.5), 0.0),
    ]


def presets_command(*args) -> str:
    out = io.StringIO()
    call_command("ftt_mode_presets", *args, stdout=out)
    return out.getvalue()


def test_the_command_lists_the_presets_and_prints_one_ready_to_paste():
    listed = presets_command().splitlines()
    assert [line.split()[0] for line in listed[1:]] == [p.name for p in PRESETS]
    assert f"  autoware    {preset('autoware').summary}" in listed
    assert presets_command("mavros") == preset("mavros").document
    with pytest.raises(CommandError, match="no preset mavlink .there are: bool, string"):
        presets_command("mavlink")
    with translation.override("de"):
        german = presets_command().splitlines()
    assert german[0] == "Vorlagen für params.mode_sources (eine mit ihrem Namen ausgeben):"
    assert german[-1].startswith("  deadman     ein Totmannknopf am Joystick")


def test_the_docs_show_every_preset_as_the_command_prints_it_and_no_other():
    docs = (Path(__file__).parents[3] / "docs" / "collector.md").read_text()
    section = docs.split("### Mode presets")[1].split("\n### ")[0]
    shown = re.findall(r"^\*\*(\w+)\*\*: ([^\n]*)\n\n```yaml\n(.*?)```", section, re.M | re.S)
    assert shown == [(p.name, str(p.summary), presets_command(p.name)) for p in PRESETS]
    assert section.count("```yaml") == len(PRESETS)
