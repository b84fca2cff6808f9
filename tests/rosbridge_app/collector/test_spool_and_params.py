import uuid
from datetime import UTC, datetime

import pytest

from rosbridge_app.collector import params as P
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.spool import Spool


def test_spool_survives_reopening_and_keeps_order(tmp_path):
    path = tmp_path / "spool.sqlite3"
    box = Spool(path)
    uids = [uuid.uuid4() for _ in range(3)]
    at = datetime(2026, 1, 1, tzinfo=UTC)
    box.append([Event("gps", at, {"lat": i, "robot_stamp": at}, uid=u) for i, u in enumerate(uids)])
    box.append([Event("image", at, {"master": "x"}, blob=b"\xff\xd8jpeg")])
    box.set_state("logging", "1")
    box.close()
    again = Spool(path)
    rows = again.peek(10)
    assert [e.uid for _, e in rows][:3] == uids
    assert rows[0][1].data["robot_stamp"] == at
    assert rows[3][1].blob == b"\xff\xd8jpeg"
    again.remove([rows[0][0], rows[1][0]])
    assert len(again) == 2
    assert again.get_state("logging") == "1"


def test_parameters_file_round_trip_keeps_other_nodes(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("other_node:\n  ros__parameters:\n    x: 1\n")
    values = {name: spec.default for name, spec in P.SPECS.items()}
    values["topics.gps_fix"] = "/robot/fix"
    P.write_file(path, values)
    assert P.read_file(path)["topics.gps_fix"] == "/robot/fix"
    assert "other_node" in path.read_text()


@pytest.mark.parametrize(
    "name,value",
    [
        ("params.pose_min_distance", -1.0),
        ("params.pose_min_distance", "far"),
        ("params.robot_mode_type", "joystick"),
        ("params.use_tf", 1),
        ("set_ftt_logging_service", ""),
    ],
)
def test_bad_parameter_values_are_refused_with_a_reason(name, value):
    with pytest.raises(P.InvalidParameter, match=name):
        P.check(name, value)
