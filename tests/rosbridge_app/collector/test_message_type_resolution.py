"""The parameter check resolves message types from interface packages only: a
module an operator names as a package is never imported (nothing it would run
reaches the server's log)."""

import sys

import pytest

from rosbridge_app.collector import params as P
from rosbridge_app.collector.bag import rclpy_type
from rosbridge_app.collector.message_fields import is_interface_package, message_class


def test_a_module_named_as_a_message_package_is_refused_without_importing_it(capfd):
    sys.modules.pop("this", None)
    text = "sources: [{topic: /s, type: this/msg/Zen, field: data, auto: [1]}]"
    with pytest.raises(P.InvalidParameter, match="unknown message type this/msg/Zen"):
        P.check("params.mode_sources", text)
    out, err = capfd.readouterr()
    assert "Beautiful is better than ugly" not in out + err
    assert "this" not in sys.modules


def test_the_collector_and_the_bag_player_never_import_a_module_a_type_names(capfd):
    """A type reaches the robot's side from parameters stored before the check,
    from the ROS graph (snapshots) or from a bag (the player): none runs a module."""
    sys.modules.pop("this", None)
    for resolve, typename in (
        (message_class, "this/msg/Zen"),
        (message_class, "this/srv/Zen"),
        (rclpy_type, "this/msg/Zen"),
    ):
        with pytest.raises(ImportError, match="no interface package"):
            resolve(typename)
    out, err = capfd.readouterr()
    assert "Beautiful is better than ugly" not in out + err
    assert "this" not in sys.modules
    assert message_class("std_msgs/msg/String")().data == ""


def test_interface_packages_are_told_from_other_modules():
    assert is_interface_package("std_msgs") and is_interface_package("industrial_msgs")
    assert not any(map(is_interface_package, ("this", "os", "django", "Std_msgs", "a.b")))


def test_a_parameter_text_of_thousands_of_mode_sources_is_refused_at_once():
    def sources(count):
        lines = (
            f"  - {{topic: /s{i}, type: std_msgs/msg/String, field: data, auto: [A]}}\n"
            for i in range(count)
        )
        return "sources:\n" + "".join(lines)

    with pytest.raises(P.InvalidParameter, match="longer than 20000 characters"):
        P.check("params.mode_sources", sources(3000))
    assert P.check("params.mode_sources", sources(50)) == sources(50)
