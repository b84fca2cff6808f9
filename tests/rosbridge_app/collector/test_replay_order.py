"""After an outage, live data overtakes the spooled backlog without changing where
anything is stored: the writer's order (collector/replay.py), spool to database."""

from datetime import UTC, datetime, timedelta

import pytest

from events.models import Segment
from rosbridge_app.collector import events as ev
from rosbridge_app.collector import replay
from rosbridge_app.collector.disk_guard import DiskGuard
from rosbridge_app.collector.event_writer import EventWriter
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.held import Held
from rosbridge_app.collector.replay import ReplayOrder
from rosbridge_app.collector.spool import Spool
from telemetry.models import LocalPose, MapImage, Pose
from tests.support.images import grey_png

pytestmark = pytest.mark.django_db
SLICE = 10


def _fixes(start: datetime, count: int) -> list[Event]:
    out = []
    for i in range(count):
        t = start + timedelta(seconds=0.1 * (i + 1))
        out.append(Event(ev.GPS_FIX, t, {"lon": 7.0, "lat": 50.0 + i * 1e-6, "robot_stamp": t}))
        out.append(Event(ev.LOCAL_POSE, t, {"x": float(i), "y": 0.0, "frame": "map", "yaw": 0.0}))
    return out


def _map(t: datetime, level: int) -> Event:
    grid = {"frame": "map", "width": 2, "height": 2, "resolution": 0.1}
    grid.update(origin_x=0.0, origin_y=0.0, checksum=str(level))
    return Event(ev.MAP, t, grid, blob=grey_png(level, size=(2, 2)))


@pytest.mark.parametrize("restart", [False, True], ids=["one run", "restarted midway"])
def test_a_live_switch_is_stored_before_the_backlog_and_everything_once(
    leg, tmp_path, media_root, restart
):
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    auto, ito_at = t0, t0 + timedelta(seconds=10)
    ranges = {"auto": _fixes(auto, 20), "ito": _fixes(ito_at, 40)}
    backlog = [
        Event(ev.START, t0),
        Event(ev.MODE, auto, {"mode": "auto"}),
        *ranges["auto"][:20],
        _map(auto + timedelta(seconds=1), 10),
        *ranges["auto"][20:],
        Event(ev.MODE, ito_at, {"mode": "ito"}),
        *ranges["ito"][:40],
        _map(ito_at + timedelta(seconds=2), 20),
        *ranges["ito"][40:],
    ]
    spool = Spool(tmp_path / "spool.sqlite3")
    spool.append(backlog)
    event_writer = EventWriter(lambda: leg)
    order = ReplayOrder(spool, SLICE)
    order.write_next(event_writer)  # the database is back: the writer has found the backlog

    # Published after the restore, while the backlog is replayed.
    live_at = t0 + timedelta(minutes=5)
    live = [Event(ev.MODE, live_at, {"mode": "auto"}), *_fixes(live_at, 3)]
    live.append(_map(live_at + timedelta(seconds=1), 30))
    spool.append(live)

    backlog_left_when_live_stored = None
    turns = restarts = 0
    while len(spool):
        if restart and order.replaying and turns == 1:
            # A crash or restart in the middle: the spool says where the backlog goes.
            event_writer, order = EventWriter(lambda: leg), ReplayOrder(spool, SLICE)
            restarts += 1
        order.write_next(event_writer)
        turns += 1
        assert turns < 100
        if backlog_left_when_live_stored is None and Segment.objects.filter(uid=live[0].uid):
            spooled = {str(e.uid) for _, e in spool.peek(1000)}
            backlog_left_when_live_stored = sum(str(e.uid) in spooled for e in backlog)

    assert backlog_left_when_live_stored and backlog_left_when_live_stored > SLICE
    assert restarts == (1 if restart else 0)
    masters = list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start"))
    assert [(m.segment_type_id, m.start) for m in masters] == [
        ("auto", auto),
        ("ito", ito_at),
        ("auto", live_at),
    ]
    assert [m.end for m in masters] == [ito_at, live_at, None]
    expected = {**ranges, "live": live[1:7]}
    for master, (name, events) in zip(masters, expected.items(), strict=True):
        stored = {str(u) for u in Pose.objects.filter(segment=master).values_list("uid", flat=True)}
        stored |= {
            str(u) for u in LocalPose.objects.filter(segment=master).values_list("uid", flat=True)
        }
        assert stored == {str(e.uid) for e in events}, name
    assert Pose.objects.count() + LocalPose.objects.count() == 2 * (20 + 40 + 3)
    # The live map was newer than the backlog's: it is still the shift's current one.
    maps = list(MapImage.objects.order_by("received", "id").values_list("checksum", flat=True))
    assert maps == ["10", "20", "30"]


@pytest.mark.parametrize("seconds", [60.0, 0.0], ids=["quick slices", "slow slices"])
def test_backlog_slices_grow_while_each_is_stored_within_the_time_a_live_switch_may_wait(
    leg, tmp_path, monkeypatch, seconds
):
    # SLICE_SECONDS is how long a live switch may wait behind one backlog slice.
    monkeypatch.setattr(replay, "SLICE_SECONDS", seconds)
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    positions = _fixes(t0 + timedelta(seconds=1), 200)
    spool = Spool(tmp_path / "spool.sqlite3")
    spool.append([Event(ev.START, t0), Event(ev.MODE, t0, {"mode": "auto"}), *positions])
    order = ReplayOrder(spool, SLICE)
    order.write_next(EventWriter(lambda: leg))  # finds the backlog, applies its segment changes

    event_writer, taken = EventWriter(lambda: leg), []
    while len(spool):
        taken.append(order.write_next(event_writer))
        assert len(taken) < 100

    assert Pose.objects.count() + LocalPose.objects.count() == len(positions)
    if seconds:
        # Stored far within the time: slices grow to their bound, fewer turns.
        assert max(taken) == SLICE * replay.MAX_SLICES
        assert len(taken) < len(positions) // SLICE
    else:
        assert max(taken) == SLICE


def test_a_live_switch_is_committed_before_what_was_spooled_after_it(leg, tmp_path):
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    before, after = _fixes(t0, 3), _fixes(t0 + timedelta(seconds=1), 3)
    switch = Event(ev.MODE, t0 + timedelta(seconds=1), {"mode": "ito"})
    spool = Spool(tmp_path / "spool.sqlite3")
    spool.append([Event(ev.START, t0), *before, switch, *after])
    order, event_writer = ReplayOrder(spool, 100), EventWriter(lambda: leg)

    assert order.write_next(event_writer) == 1  # the start alone
    assert order.write_next(event_writer) == len(before) + 1
    # The new master is in the database while the positions after it still wait.
    assert Segment.objects.get(uid=switch.uid).segment_type_id == "ito"
    assert len(spool) == len(after)
    assert order.write_next(event_writer) == len(after)
    assert Pose.objects.filter(segment__uid=switch.uid).count() == 3


def test_a_switch_ends_its_slice_and_the_writer_knows_it_is_stored(leg, tmp_path):
    """The collector's writer stores a switch ahead of its heartbeat: slices
    until the one that held the switch (runtime._write_change)."""
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    spool = Spool(tmp_path / "spool.sqlite3")
    # Live, not a backlog: fewer records pending than a quarter of a slice.
    event_writer, order = EventWriter(lambda: leg), ReplayOrder(spool, 100)
    spool.append([Event(ev.START, t0), Event(ev.MODE, t0, {"mode": "auto"})])
    while order.write_next(event_writer):
        pass
    switch_at = t0 + timedelta(seconds=5)
    spool.append(
        [*_fixes(t0, 2), Event(ev.MODE, switch_at, {"mode": "ito"}), *_fixes(switch_at, 2)]
    )
    while order.write_next(event_writer):
        if order.stored_change:
            break
    assert Segment.objects.get(leg=leg, parent=None, end=None).segment_type_id == "ito"
    assert len(spool) == 4  # the positions after the switch wait for the next turn
    assert order.write_next(event_writer) == 4 and not order.stored_change


def test_a_live_switch_stored_with_a_backlog_slice_is_known_as_stored(leg, tmp_path):
    """The backlog slice stored after the live one in the same turn does not
    hide the switch from the writer."""
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    spool = Spool(tmp_path / "spool.sqlite3")
    spool.append([Event(ev.START, t0), Event(ev.MODE, t0, {"mode": "auto"}), *_fixes(t0, 30)])
    event_writer, order = EventWriter(lambda: leg), ReplayOrder(spool, SLICE)
    order.write_next(event_writer)  # the backlog found, its segment changes applied
    switch = Event(ev.MODE, t0 + timedelta(seconds=10), {"mode": "ito"})
    spool.append([switch])
    order.write_next(event_writer)
    assert Segment.objects.filter(uid=switch.uid).exists()
    assert order.stored_change
    assert len(spool) > 0  # the backlog's positions still wait


def test_positions_held_in_memory_do_not_wait_for_each_switch_of_a_small_spool(leg, tmp_path):
    """The disk filled during an outage: the spool holds a few switches, memory
    the live data after them. The live data is stored at the second turn, not
    behind one turn per spooled switch."""
    t0 = datetime.now(UTC) + timedelta(minutes=1)
    spool = Spool(tmp_path / "spool.sqlite3")
    spooled = [Event(ev.START, t0)]
    for i, mode in enumerate(["auto", "ito", "auto", "ito"]):
        at = t0 + timedelta(seconds=i)
        spooled += [Event(ev.MODE, at, {"mode": mode}), *_fixes(at, 2)]
    spool.append(spooled)
    held = Held(DiskGuard(tmp_path / "spool.sqlite3", budget=None, headroom=0))
    live = _fixes(t0 + timedelta(seconds=10), 1)
    for event in live:
        held.add(event)
    order, event_writer = ReplayOrder(spool, 100, held=held), EventWriter(lambda: leg)
    assert len(spool) < order.backlog  # small: by its size alone not a backlog

    order.write_next(event_writer)  # the spool's switches
    order.write_next(event_writer)
    assert Pose.objects.filter(uid=live[0].uid).exists()
    while order.write_next(event_writer):
        pass
    masters = Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start")
    assert [m.segment_type_id for m in masters] == ["auto", "ito", "auto", "ito"]
    assert Pose.objects.count() == 4 * 2 + 1
