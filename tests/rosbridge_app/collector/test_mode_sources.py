"""Mode from any topic: checks, value mapping, combination and hysteresis (no ROS),
and a recording with the robot's own message type imported with the same rules."""

from datetime import UTC, datetime, timedelta
from pathlib import Path
from types import SimpleNamespace as NS

import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from exchange.bag import import_bag
from rosbridge_app.collector import events as ev
from rosbridge_app.collector import params as P
from rosbridge_app.collector import reason_rules
from rosbridge_app.collector.bag import bag_events
from rosbridge_app.collector.message_fields import (
    folder_types,
    installed_fields,
    recorded_fields,
)
from rosbridge_app.collector.mode_sources import Combiner, parse

T0 = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)
ROBOT_MSGS = Path(__file__).parent / "robot_msgs" / "ftt_robot_msgs"
# A MAVROS-like flight mode, vetoed by an e-stop: the combined rule of docs/collector.md.
MAVROS_WITH_ESTOP = """
rule: any_ito
sources:
  - {topic: /mavros/state, type: ftt_robot_msgs/msg/State, field: mode,
     auto: [OFFBOARD, AUTO.MISSION], ito: [MANUAL, POSCTL]}
  - {topic: /estop, type: std_msgs/msg/Bool, field: data, ito: [true]}
"""


def at(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        (MAVROS_WITH_ESTOP, "unknown message type ftt_robot_msgs/msg/State"),
        (
            "sources: [{topic: /joy, type: sensor_msgs/msg/Joy, field: 'button[4]', ito: [1]}]",
            "sensor_msgs/msg/Joy has no field button",
        ),
        (
            "sources: [{topic: /s, type: std_msgs/msg/String, field: data.x, auto: [A]}]",
            "data.x goes into a field that is not a message",
        ),
        ("sources: [{topic: /s, type: std_msgs/msg/String, field: data}]", "maps no value"),
        ("sources: [{topic: /s, type: std_msgs/String, field: data}]", "not package/msg/Name"),
    ],
)
def test_the_parameter_check_names_what_is_wrong(text, named):
    with pytest.raises(P.InvalidParameter, match="params.mode_sources") as caught:
        P.check("params.mode_sources", text)
    assert named in str(caught.value)


def test_installed_types_with_nested_and_indexed_fields_pass_the_check():
    text = """
    sources:
      - {topic: /joy, type: sensor_msgs/msg/Joy, field: "buttons[4]", ito: [1]}
      - {topic: /fix, type: sensor_msgs/msg/NavSatFix, field: status.status,
         auto: [{min: 0, max: 2}], default: ito}
    """
    assert P.check("params.mode_sources", text) == text


def test_sets_ranges_defaults_and_the_estop_veto():
    config = parse(
        """
        rule: any_ito
        sources:
          - {topic: /level, type: std_msgs/msg/Int32, field: data,
             auto: [{min: 3, max: 5}], ito: [0, 1], default: unknown}
          - {topic: /estop, type: std_msgs/msg/Bool, field: data, ito: [true]}
        """
    )
    combiner = Combiner(config)
    said = []
    for t, index, value in [
        (0, 0, 2),  # says nothing: no mode yet
        (1, 0, 4),  # AUTO
        (2, 1, False),  # e-stop released: no opinion
        (3, 1, True),  # pressed: ITO whatever the level says
        (4, 0, 5),  # a switch during the e-stop changes nothing
        (5, 1, False),  # released: the level (AUTO) decides again
        (6, 0, 1),
    ]:
        said += combiner.offer(index, NS(data=value), at(t))
    assert [s[:2] for s in said] == [
        ("auto", at(1)),
        ("ito", at(3)),
        ("auto", at(5)),
        ("ito", at(6)),
    ]


def test_an_index_the_message_does_not_have_says_nothing():
    config = parse(
        "sources: [{topic: /joy, type: sensor_msgs/msg/Joy, field: 'buttons[4]', ito: [1]}]"
    )
    combiner = Combiner(config)
    assert combiner.offer(0, NS(buttons=[0, 1]), at(0)) == []
    assert combiner.offer(0, NS(buttons=[0, 0, 0, 0, 1]), at(1))[0][:2] == ("ito", at(1))


def test_hysteresis_ignores_flicker_and_switches_when_it_ran_out():
    config = parse(
        "sources: [{topic: /m, type: std_msgs/msg/String, field: data,"
        " auto: [AUTO], ito: [MANUAL], hysteresis: 1.0}]"
    )
    combiner = Combiner(config)
    said = []
    for t, value in [(0, "AUTO"), (1.5, "AUTO"), (2, "MANUAL"), (2.5, "AUTO"), (3, "MANUAL")]:
        said += combiner.offer(0, NS(data=value), at(t))
    said += combiner.tick(at(4.2))
    assert [s[:2] for s in said] == [("auto", at(1)), ("ito", at(4))]


def stamped(seconds: float) -> NS:
    return NS(sec=int(seconds), nanosec=int(round(seconds % 1 * 1e9)))


def test_a_source_with_a_stamp_switches_at_the_robots_time_however_late_it_arrives():
    config = parse(
        """
        sources:
          - {topic: /state, type: ftt_robot_msgs/msg/State, field: mode,
             auto: [OFFBOARD], ito: [MANUAL]}
          - {topic: /op, type: ftt_robot_msgs/msg/OperationModeState, field: mode,
             auto: [2], ito: [1], stamp: stamp, hysteresis: 0.5}
        """
    )
    combiner = Combiner(config)
    t = T0.timestamp()
    state = NS(header=NS(stamp=stamped(t + 1)), mode="OFFBOARD")
    assert combiner.offer(0, state, at(3.5), sent=at(1.01)) == [("auto", at(1), at(1), 0.0)]
    # The latched subscription's copy of the same message is no news.
    assert combiner.offer(0, state, at(3.6), sent=at(1.01)) is None
    # A field named by `stamp`, and a hysteresis counted from it.
    assert combiner.offer(1, NS(stamp=stamped(t + 5), mode=1), at(5.2)) == []
    assert combiner.offer(1, NS(stamp=stamped(t + 5.6), mode=1), at(6.2)) == [
        ("ito", at(5.5), at(5.5), 0.0)
    ]


def test_a_source_without_a_stamp_switches_when_sent_within_the_interval_since_its_last():
    config = parse("sources: [{topic: /m, type: std_msgs/msg/String, field: data,"
                   " auto: [AUTO], ito: [MANUAL]}]")  # fmt: skip
    combiner = Combiner(config)
    combiner.offer(0, NS(data="AUTO"), at(0.2), sent=at(0))
    combiner.offer(0, NS(data="AUTO"), at(1.2), sent=at(1))
    assert combiner.offer(0, NS(data="MANUAL"), at(4.0), sent=at(2)) == [("ito", at(2), at(2), 1.0)]


def test_a_stamp_path_must_name_a_time():
    text = (
        "sources: [{topic: /s, type: ftt_robot_msgs/msg/State, field: mode,"
        " auto: [A], stamp: header.frame_id}]"
    )
    with pytest.raises(ValueError, match="header.frame_id is not a time stamp"):
        parse(text, fields_of=recorded_fields(robot_store()))


def robot_store():
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(folder_types(ROBOT_MSGS))
    return store


def _write_bag(path: Path, script: list) -> None:
    """A rosbag2 MCAP with the robot's own State type (definitions from its .msg
    files, carried in the recording), an e-stop and fixes."""
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(folder_types(ROBOT_MSGS))
    State = store.types["ftt_robot_msgs/msg/State"]
    Bool = store.types["std_msgs/msg/Bool"]
    Fix = store.types["sensor_msgs/msg/NavSatFix"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    Status = store.types["sensor_msgs/msg/NavSatStatus"]
    import numpy as np

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {
            "/mavros/state": writer.add_connection(
                "/mavros/state", "ftt_robot_msgs/msg/State", typestore=store
            ),
            "/estop": writer.add_connection("/estop", "std_msgs/msg/Bool", typestore=store),
            "/gps_fix": writer.add_connection(
                "/gps_fix", "sensor_msgs/msg/NavSatFix", typestore=store
            ),
        }
        for t, topic, value in script:
            ns = int(at(t).timestamp() * 1e9)
            header = Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="gps")
            if topic == "/mavros/state":
                msg = State(header, True, True, True, False, value, 4)
            elif topic == "/estop":
                msg = Bool(data=value)
            else:
                msg = Fix(
                    header,
                    Status(status=0, service=1),
                    value,
                    8.0,
                    0.0,
                    np.zeros(9),
                    0,
                )
            writer.write(conns[topic], ns, store.serialize_cdr(msg, msg.__msgtype__))


@pytest.mark.django_db
def test_a_recording_with_the_robots_own_type_gives_the_scripted_segments(
    tmp_path, vehicle, media_root
):
    flight = {0: "MANUAL", 10: "AUTO.MISSION", 20: "POSCTL", 30: "OFFBOARD"}
    script = []
    for tenth in range(400):
        t = tenth / 10
        script.append((t, "/gps_fix", 50.0 + t * 1e-5))
        if tenth % 10 == 0:
            mode = flight[max(k for k in flight if k <= t)]
            script.append((t + 0.01, "/mavros/state", mode))
            script.append((t + 0.02, "/estop", 12 <= t < 16 or 28 <= t < 33))
    _write_bag(tmp_path / "flight", script)
    events = bag_events(tmp_path / "flight", {"params.mode_sources": MAVROS_WITH_ESTOP})
    modes = [
        (e.data["mode"], round((e.at - T0).total_seconds(), 2)) for e in events if e.kind == ev.MODE
    ]
    # The e-stop pressed at 28 keeps ITO through the switch to OFFBOARD at 30; the
    # first segment starts at the fix before the first mode (collector/unknown_mode.py).
    assert modes == [
        ("ito", 0.0),
        ("auto", 10.01),
        ("ito", 12.02),
        ("auto", 16.02),
        ("ito", 20.01),
        ("auto", 33.02),
    ]
    assert sum(e.kind == ev.GPS_FIX for e in events) > 30
    # The importer checks the sources against the recording's own definitions
    # (ftt_robot_msgs is not installed) and stores the same segments.
    result = import_bag(
        tmp_path / "flight", vehicle=vehicle, params={"params.mode_sources": MAVROS_WITH_ESTOP}
    )
    stored = result.leg.segments.filter(parent__isnull=True).order_by("start")
    assert [(m.segment_type_id, m.start) for m in stored] == [
        (mode, T0 + timedelta(seconds=t)) for mode, t in modes
    ]


@pytest.mark.django_db
def test_a_recording_whose_mode_comes_late_keeps_its_track_in_a_segment_of_unknown_mode(
    tmp_path, vehicle, media_root
):
    from reports.selectors.statistics import event_statistics
    from tests.support.fkie import gps_path_length

    # The flight controller says its state only on change, the first time 15 s
    # after the first fix: longer than params.unknown_mode_wait (10 s).
    script = [(tenth / 10, "/gps_fix", 50.0 + tenth * 1e-5) for tenth in range(250)]
    script += [(15.0, "/mavros/state", "MANUAL"), (20.0, "/mavros/state", "OFFBOARD")]
    _write_bag(tmp_path / "late", sorted(script, key=lambda step: step[0]))
    state_only = MAVROS_WITH_ESTOP.split("  - {topic: /estop")[0]
    result = import_bag(
        tmp_path / "late", vehicle=vehicle, params={"params.mode_sources": state_only}
    )
    stored = list(result.leg.segments.filter(parent__isnull=True).order_by("start"))
    assert [(m.segment_type_id, m.start) for m in stored] == [
        ("unknown", at(0)),
        ("ito", at(15)),
        ("auto", at(20)),
    ]
    first = stored[0].poses.order_by("robot_stamp").first()
    assert (first.point.x, first.point.y) == (8.0, 50.0)
    figures = event_statistics(result.leg.shift.test_event).overall
    assert figures.unknown_seconds == 15.0
    # Its track up to the next segment's start, measured as every distance is.
    assert figures.unknown_distance == pytest.approx(
        gps_path_length([(8.0, 50.0), (8.0, 50.0015)]), rel=1e-6
    )
    assert figures.total_distance == pytest.approx(
        figures.auto_distance + figures.manual_distance + figures.unknown_distance
    )


def test_reason_rules_suggest_the_first_that_fired_within_the_window():
    rules = reason_rules.parse(
        """
        window: 2.0
        rules:
          - {topic: /estop, type: std_msgs/msg/Bool, field: data, values: [true], reason: safety}
          - {topic: /planner, type: std_msgs/msg/Int32, field: data, values: [{min: 3}],
             reason: planner}
          - {topic: /loc, type: std_msgs/msg/Empty, silent: 1.0, reason: other}
        """,
        installed_fields,
    )
    watcher = reason_rules.ReasonWatcher(rules)
    watcher.offer("/loc", NS(), at(0))
    watcher.offer("/planner", NS(data=4), at(0.5))
    assert watcher.reason_at(at(0.8)) == "planner"
    watcher.offer("/planner", NS(data=0), at(0.9))
    watcher.offer("estop", NS(data=True), at(1.0))  # the same topic without its slash
    assert watcher.reason_at(at(1.0)) == "safety"
    watcher.offer("/estop", NS(data=False), at(1.2))  # a short press still counts
    assert watcher.reason_at(at(2.5)) == "safety"
    assert watcher.reason_at(at(3.5)) == "other"  # e-stop pressed too long ago; /loc silent
    watcher.offer("/loc", NS(), at(3.6))
    assert watcher.reason_at(at(3.7)) is None


def test_a_reason_rule_on_a_field_the_type_lacks_is_refused():
    with pytest.raises(P.InvalidParameter, match="std_msgs/msg/Bool has no field value"):
        P.check(
            "params.reason_rules",
            "rules: [{topic: /e, type: std_msgs/msg/Bool, field: value, values: [1], reason: x}]",
        )
