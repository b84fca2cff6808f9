"""Nothing dropped while the mode is unknown: positions before the first mode join
the first segment, or a segment of unknown mode once the wait is over (no ROS)."""

from datetime import UTC, datetime, timedelta
from types import SimpleNamespace as NS

import pytest

from rosbridge_app.collector import events as ev
from rosbridge_app.collector.pipeline import Pipeline

T0 = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)
WAIT = 10.0


def at(seconds: float) -> datetime:
    return T0 + timedelta(seconds=seconds)


def fix(seconds: float, lat: float) -> NS:
    ns = int(at(seconds).timestamp() * 1e9)
    return NS(
        header=NS(stamp=NS(sec=ns // 10**9, nanosec=ns % 10**9)),
        status=NS(status=0),
        latitude=lat,
        longitude=8.0,
        altitude=0.0,
        position_covariance=[0.0] * 9,
        position_covariance_type=0,
    )


def pose(x: float) -> dict:
    return {"x": x, "y": 0.0, "yaw": 0.0, "frame": "map", "robot_stamp": None}


def drive(pipe: Pipeline, seconds: float, start: float = 0.0) -> None:
    """Driving north (GPS) and east (local) at 10 Hz, one metre a second."""
    for tenth in range(round(start * 10), round((start + seconds) * 10)):
        t = tenth / 10
        pipe.on_fix(fix(t, 50.0 + t * 9e-6), at(t))
        pipe.on_local_value(pose(t), at(t))


@pytest.fixture
def pipe():
    events: list = []
    pipeline = Pipeline(events.append, {"params.unknown_mode_wait": WAIT})
    pipeline.events = events
    pipeline.start_logging(at(0))
    return pipeline


def masters(events) -> list[tuple[str, float]]:
    return [(e.data["mode"], (e.at - T0).total_seconds()) for e in events if e.kind == ev.MODE]


def positions(events, kind) -> list[float]:
    return [(e.at - T0).total_seconds() for e in events if e.kind == kind]


def test_a_mode_within_the_wait_starts_the_first_segment_at_the_first_position(pipe):
    known = Pipeline(lambda e: None)
    known_events: list = []
    known.sink = known_events.append
    known.start_logging(at(0))
    known.on_mode_value("auto", at(0))
    drive(known, 9.0)

    drive(pipe, 7.0)
    assert masters(pipe.events) == []  # held, not yet stored
    pipe.on_mode_value("auto", at(7.0))
    drive(pipe, 2.0, start=7.0)
    # The same segment and the same tracks as if the mode had been known from the start.
    assert masters(pipe.events) == [("auto", 0.0)]
    mode = next(e for e in pipe.events if e.kind == ev.MODE)
    assert mode.data["gps"] == [8.0, 50.0] and mode.data["local"] == [0.0, 0.0, "map"]
    for kind in (ev.GPS_FIX, ev.LOCAL_POSE):
        assert positions(pipe.events, kind) == positions(known_events, kind)
        assert positions(pipe.events, kind)[0] == 0.0


def test_after_the_wait_a_segment_of_unknown_mode_holds_the_track_until_the_mode_is_known(pipe):
    drive(pipe, 15.0)
    pipe.on_mode_value("ito", at(15.0))
    drive(pipe, 2.0, start=15.0)
    pipe.stop_logging(at(17.0))
    assert masters(pipe.events) == [("unknown", 0.0), ("ito", 15.0)]
    events = pipe.events
    switch = next(i for i, e in enumerate(events) if e.kind == ev.MODE and e.data["mode"] == "ito")
    for kind in (ev.GPS_FIX, ev.LOCAL_POSE):
        before = positions(events[:switch], kind)
        # Every second of the 15 s before the mode was known is in the unknown segment.
        assert before[0] == 0.0 and before[-1] >= 14.0
        assert all(b - a <= 1.0 for a, b in zip(before, before[1:], strict=False))
    unknown = next(e for e in events if e.kind == ev.MODE)
    assert unknown.data["suggested_reason"] is None


def test_a_wait_without_new_positions_ends_at_the_tick(pipe):
    drive(pipe, 1.0)
    pipe.tick(at(5.0))
    assert masters(pipe.events) == []
    pipe.tick(at(10.0))
    assert masters(pipe.events) == [("unknown", 0.0)]
    assert positions(pipe.events, ev.GPS_FIX)[0] == 0.0


def test_logging_stopped_before_the_mode_is_known_keeps_the_track(pipe):
    drive(pipe, 3.0)
    pipe.stop_logging(at(3.0))
    assert masters(pipe.events) == [("unknown", 0.0)]
    assert positions(pipe.events, ev.LOCAL_POSE)[0] == 0.0
    assert pipe.events[-1].kind == ev.STOP
    # The next logging waits afresh; a mode heard now opens its segment at once.
    pipe.on_mode_value("auto", at(4.0))
    pipe.start_logging(at(5.0))
    assert masters(pipe.events)[-1] == ("auto", 5.0)


def test_a_wait_of_zero_opens_the_unknown_segment_at_the_first_position():
    events: list = []
    pipe = Pipeline(events.append, {"params.unknown_mode_wait": 0.0})
    pipe.start_logging(at(0))
    drive(pipe, 0.1)
    assert masters(events) == [("unknown", 0.0)]


def test_nothing_is_held_while_logging_is_off():
    events: list = []
    pipe = Pipeline(events.append, {"params.unknown_mode_wait": 0.0})
    drive(pipe, 5.0)
    assert events == []


def listening_pipe() -> Pipeline:
    """A live collector connected to a mode publisher before the first position."""
    events: list = []
    pipeline = Pipeline(events.append, {"params.unknown_mode_wait": WAIT})
    pipeline.events = events
    pipeline.mode_publisher = lambda: True
    pipeline.start_logging(at(0))
    return pipeline


def test_only_a_latched_or_periodic_first_mode_takes_the_track_held_before_it():
    # A latched sample: the robot said AUTO a minute before the collector joined.
    latched = listening_pipe()
    drive(latched, 3.0)
    latched.on_mode_value("auto", at(-60.0), received=at(3.0))
    assert masters(latched.events) == [("auto", 0.0)]

    # A periodic mode: heard at 0.8 s and again a period later.
    periodic = listening_pipe()
    drive(periodic, 0.8)
    periodic.on_mode_value("auto", at(0.8))
    drive(periodic, 1.0, start=0.8)
    assert masters(periodic.events) == []  # not yet known to be periodic
    periodic.on_mode_value("auto", at(1.8))
    assert masters(periodic.events) == [("auto", 0.0)]

    # A 2 Hz mode whose first message came a period late (a busy robot, the
    # mode topic matched after the positions' topic) is periodic all the same.
    late = listening_pipe()
    drive(late, 0.7)
    late.on_mode_value("auto", at(0.7))
    drive(late, 0.5, start=0.7)
    late.on_mode_value("auto", at(1.2))
    assert masters(late.events) == [("auto", 0.0)]

    # A switch after 4 s of silence; the 10 Hz repeats that follow cannot make
    # it periodic: the 4 s before it have no known mode, the switch keeps its time.
    on_change = listening_pipe()
    drive(on_change, 4.0)
    for tenth in range(40, 50):
        on_change.on_mode_value("auto", at(tenth / 10))
    drive(on_change, 1.0, start=4.0)
    assert masters(on_change.events) == [("unknown", 0.0), ("auto", 4.0)]
    switch = next(i for i, e in enumerate(on_change.events) if e.data.get("mode") == "auto")
    before = positions(on_change.events[:switch], ev.GPS_FIX)
    assert before[0] == 0.0 and 3.0 <= before[-1] < 4.0


def test_a_first_mode_that_cannot_prove_periodic_is_stored_as_a_switch_while_logging_goes_on():
    pipe = listening_pipe()
    drive(pipe, 2.0)
    pipe.on_mode_value("ito", at(2.0))
    drive(pipe, 9.9, start=2.0)
    assert masters(pipe.events) == []  # a repeat within the wait would make it periodic
    drive(pipe, 0.2, start=11.9)
    assert masters(pipe.events) == [("unknown", 0.0), ("ito", 2.0)]
