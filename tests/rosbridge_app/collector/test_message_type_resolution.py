"""The parameter check resolves message types from interface packages only: a
module an operator names as a package is never imported (nothing it would run
reaches the server's log)."""

import sys

import pytest

from rosbridge_app.collector import params as P
from rosbridge_app.collector.message_fields import is_interface_package


def test_a_module_named_as_a_message_package_is_refused_without_importing_it(capfd):
    sys.modules.pop("this", None)
    text = "sources: [{topic: /s, type: this/msg/Zen, field: data, auto: [1]}]"
    with pytest.raises(P.InvalidParameter, match="unknown message type this/msg/Zen"):
        P.check("params.mode_sources", text)
    out, err = capfd.readouterr()
    assert "Beautiful is better than ugly" not in out + err
    assert "this" not in sys.modules


def test_interface_packages_are_told_from_other_modules():
    assert is_interface_package("std_msgs") and is_interface_package("industrial_msgs")
    assert not any(map(is_interface_package, ("this", "os", "django", "Std_msgs", "a.b")))
