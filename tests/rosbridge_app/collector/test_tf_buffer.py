import math

import pytest

from rosbridge_app.collector.tf_buffer import TfBuffer, TfLookupError, Transform


def yaw_q(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def tf(x, y, yaw, t=None):
    return Transform((x, y, 0.0), yaw_q(yaw), None if t is None else int(t * 1e9))


@pytest.fixture
def buffer():
    b = TfBuffer()
    # map → odom: odom is 10 m east of map and turned by 90°.
    b.set_transform("map", "odom", tf(10, 0, math.pi / 2, 10), static=False)
    b.set_transform("map", "odom", tf(10, 0, math.pi / 2, 12))
    b.set_transform("odom", "base_link", tf(1, 0, 0, 10))
    b.set_transform("odom", "base_link", tf(3, 0, 0, 11))
    b.set_transform("base_link", "gps", tf(0.5, 0, 0), static=True)
    return b


def test_chain_applies_parent_rotation(buffer):
    # base_link is 1 m along odom's x, which points north in map.
    pose = buffer.lookup("map", "base_link", int(10e9))
    assert pose.translation[0] == pytest.approx(10)
    assert pose.translation[1] == pytest.approx(1)
    assert pose.yaw == pytest.approx(math.pi / 2)


def test_interpolates_between_stamps(buffer):
    pose = buffer.lookup("odom", "base_link", int(10.5e9))
    assert pose.translation[0] == pytest.approx(2.0)


def test_latest_common_time_without_stamp(buffer):
    pose = buffer.lookup("map", "base_link")
    # odom→base_link ends at 11 s, so 11 s is the newest time the chain knows.
    assert pose.stamp_ns == int(11e9)
    assert pose.translation[1] == pytest.approx(3)


def test_static_child_and_inverse_and_cross_branch(buffer):
    gps = buffer.lookup("map", "gps", int(11e9))
    assert gps.translation[1] == pytest.approx(3.5)
    back = buffer.lookup("base_link", "map", int(11e9))
    assert back.translation[0] == pytest.approx(-3)
    assert back.translation[1] == pytest.approx(10)
    odom_in_gps = buffer.lookup("gps", "odom", int(11e9))
    assert odom_in_gps.translation[0] == pytest.approx(-3.5)


def test_missing_or_unconnected_frames_fail_instead_of_guessing(buffer):
    with pytest.raises(TfLookupError):
        buffer.lookup("map", "camera")
    with pytest.raises(TfLookupError):
        buffer.lookup("map", "base_link", int(30e9))  # far beyond the data


def test_rejects_non_finite_transforms():
    b = TfBuffer()
    with pytest.raises(ValueError):
        b.set_transform("map", "odom", tf(float("nan"), 0, 0, 1))
