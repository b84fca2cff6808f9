"""Events → rows through the domain services (what the live collector's
writer and a bag import both do)."""

from datetime import UTC, datetime, timedelta

import pytest

from events.models import Segment, Vehicle
from events.selectors.logs import open_leg_for_vehicle
from events.services import logs
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.bag import bag_events
from rosbridge_app.collector.event_writer import EventWriter, write_events
from rosbridge_app.collector.events import Event
from telemetry.models import Image, MapImage, Pose
from tests.support.fkie import FKIE_BAG, master_path_length
from tests.support.images import grey_png, jpeg

pytestmark = pytest.mark.django_db


# The industrial_msgs/RobotMode preset of docs/collector.md ("Mode presets").
INDUSTRIAL_PRESET = """
sources:
  - {topic: robot_mode, type: industrial_msgs/msg/RobotMode, field: val, auto: [2], ito: [1]}
"""


@pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available")
@pytest.mark.parametrize(
    "params",
    [{"params.robot_mode_type": "industrial"}, {"params.mode_sources": INDUSTRIAL_PRESET}],
    ids=["robot_mode_type", "mode_source_preset"],
)
def test_fkie_bag_gives_five_masters_and_its_path_once(vehicle, media_root, params):
    # The leg must start before the bag (2019) to take its segments.
    start = datetime(2019, 4, 8, tzinfo=UTC)
    event = logs.create_test_event(at=start)
    leg = logs.create_leg(
        shift=logs.create_shift(test_event=event, vehicle=vehicle, at=start), at=start
    )
    events = bag_events(FKIE_BAG, params)
    write_events(leg, events)
    masters = list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start"))
    assert [m.segment_type_id for m in masters] == ["ito", "auto", "ito", "auto", "ito"]
    for m in masters:
        children = list(m.children.values_list("ito_reason_id", flat=True))
        assert children == (["unassigned"] if m.segment_type_id == "ito" else [])
        assert m.end is not None and m.start_position is not None
    total = sum(master_path_length(m) for m in masters)
    assert total == pytest.approx(224, rel=0.01)
    rows = Pose.objects.count()
    write_events(leg, events)  # an import run twice
    assert Pose.objects.count() == rows
    assert Segment.objects.filter(leg=leg).count() == 8


@pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available")
def test_fkie_bag_with_the_preset_gives_each_segment_of_robot_mode_type(media_root):
    start = datetime(2019, 4, 8, tzinfo=UTC)

    def imported(key: str, params: dict) -> list[tuple]:
        vehicle = Vehicle.objects.create(key=key, short_description=key)
        event = logs.create_test_event(at=start)
        shift = logs.create_shift(test_event=event, vehicle=vehicle, at=start)
        leg = logs.create_leg(shift=shift, at=start)
        write_events(leg, bag_events(FKIE_BAG, params))
        masters = Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start")
        return [(m.segment_type_id, m.start, m.end, master_path_length(m)) for m in masters]

    preset = imported("preset", {"params.mode_sources": INDUSTRIAL_PRESET})
    reference = imported("mode-type", {"params.robot_mode_type": "industrial"})
    assert len(preset) == 5
    assert [m[:3] for m in preset] == [m[:3] for m in reference]
    assert [m[3] for m in preset] == pytest.approx([m[3] for m in reference], abs=1e-9)
    assert all(m[3] > 0 for m in preset)


BASE = datetime.now(UTC)


@pytest.fixture(autouse=True)
def _base_after_fixture_legs():
    # Set per test, not at import: a long run would otherwise put these times
    # before the legs the fixtures open and the services would refuse them.
    global BASE
    BASE = datetime.now(UTC) + timedelta(minutes=1)


def at(s):
    return BASE + timedelta(seconds=s)


def test_follows_a_new_leg_and_gives_a_new_shift_its_map(leg, media_root):
    vehicle = leg.shift.vehicle
    event_writer = EventWriter(lambda: open_leg_for_vehicle(vehicle))
    png = grey_png(10, size=(2, 2))
    grid = {
        "frame": "map",
        "width": 2,
        "height": 2,
        "resolution": 0.1,
        "origin_x": 0.0,
        "origin_y": 0.0,
        "origin_yaw": 0.3,
        "checksum": "abc",
    }
    event_writer.apply(
        [
            Event(ev.START, at(0)),
            Event(ev.MODE, at(1), {"mode": "auto", "gps": [7.1, 50.6], "local": None}),
            Event(ev.MAP, at(1), grid, blob=png),
            Event(ev.GPS_FIX, at(2), {"lon": 7.1, "lat": 50.6}),
        ]
    )
    first = Segment.objects.get(leg=leg)
    assert first.poses.count() == 1 and first.segment_type_id == "auto"
    logs.close_leg(leg)
    event_writer.sync()
    assert event_writer.leg is None  # no open leg: keeps going, writes nothing
    event_writer.apply([Event(ev.GPS_FIX, at(3), {"lon": 7.2, "lat": 50.6})])
    assert Pose.objects.count() == 1
    new_shift = logs.create_shift(test_event=leg.shift.test_event, vehicle=vehicle)
    new_leg = logs.create_leg(shift=new_shift)
    event_writer.sync()
    master = Segment.objects.get(leg=new_leg, parent__isnull=True)
    assert master.segment_type_id == "auto" and master.end is None
    assert MapImage.objects.filter(shift=new_shift, origin_yaw=0.3).count() == 1


def test_a_stop_stored_after_the_next_leg_opened_starts_nothing_there(leg):
    """Ending a leg stops logging; if the next leg opens before the stop is
    stored, the stop still belongs to the leg it was given in."""
    vehicle = leg.shift.vehicle
    event_writer = EventWriter(lambda: open_leg_for_vehicle(vehicle))
    event_writer.apply([Event(ev.START, at(0)), Event(ev.MODE, at(1), {"mode": "auto"})])
    logs.close_leg(leg)
    next_leg = logs.create_leg(shift=leg.shift)
    event_writer.apply([Event(ev.STOP, at(2))])
    assert not Segment.objects.filter(leg=next_leg).exists()
    assert event_writer.leg == next_leg and not event_writer.state["logging"]


def test_images_only_for_a_new_master_and_stop_closes(leg, media_root):
    event_writer = EventWriter(lambda: leg)
    auto = Event(ev.MODE, at(1), {"mode": "auto"})
    again = Event(ev.MODE, at(2), {"mode": "auto"})  # e.g. first message after a restart
    picture = jpeg(50)
    event_writer.apply(
        [
            Event(ev.START, at(0)),
            auto,
            Event(ev.IMAGE, at(1), {"master": str(auto.uid), "suffix": "jpg"}, blob=picture),
            again,
            Event(ev.IMAGE, at(2), {"master": str(again.uid), "suffix": "jpg"}, blob=picture),
            Event(ev.STOP, at(3)),
        ]
    )
    master = Segment.objects.get(leg=leg)
    assert master.uid == auto.uid
    assert Image.objects.filter(segment=master).count() == 1
    assert master.end == at(3)


def test_a_mode_that_failed_to_store_is_the_mode_the_next_leg_starts_in(
    leg, media_root, monkeypatch
):
    from rosbridge_app.collector import event_writer as event_writer_module

    vehicle = leg.shift.vehicle
    event_writer = EventWriter(lambda: open_leg_for_vehicle(vehicle))
    event_writer.apply([Event(ev.START, at(0)), Event(ev.MODE, at(1), {"mode": "auto"})])
    stored = event_writer_module.report_mode

    def refuse_ito(leg, mode, **kwargs):
        if mode == "ito":
            raise ValueError("a broken row")
        return stored(leg, mode, **kwargs)

    monkeypatch.setattr(event_writer_module, "report_mode", refuse_ito)
    event_writer.apply([Event(ev.MODE, at(2), {"mode": "ito"})])  # logged and dropped
    assert event_writer.skipped == 1
    assert list(Segment.objects.filter(leg=leg).values_list("segment_type_id", flat=True)) == [
        "auto"
    ]
    monkeypatch.setattr(event_writer_module, "report_mode", stored)
    new_leg = logs.create_leg(shift=leg.shift)  # the GUI ends the leg and opens the next
    event_writer.sync()
    master = Segment.objects.get(leg=new_leg, parent__isnull=True)
    assert master.segment_type_id == "ito" and master.end is None


def test_interleaved_fixes_and_local_poses_land_in_the_segment_of_their_time(leg):
    """A robot sends GPS and TF turn about; a replayed backlog stores each
    position once, on the master that was open when it was received."""
    event_writer = EventWriter(lambda: open_leg_for_vehicle(leg.shift.vehicle))

    def positions(start, n):
        out = []
        for i in range(n):
            t = at(start + i * 0.1)
            out.append(Event(ev.GPS_FIX, t, {"lon": 7.0, "lat": 50.0 + (start * 100 + i) * 1e-6}))
            out.append(Event(ev.LOCAL_POSE, t, {"x": start * 100 + i, "y": 0.0, "frame": "map"}))
        return out

    batch = [Event(ev.START, at(0)), Event(ev.MODE, at(1), {"mode": "auto"})]
    batch += positions(2, 30)
    batch.append(Event(ev.MODE, at(10), {"mode": "ito"}))
    batch += positions(11, 20)
    event_writer.apply(batch)
    auto, ito = Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start")
    assert (auto.poses.count(), auto.local_poses.count()) == (30, 30)
    assert (ito.poses.count(), ito.local_poses.count()) == (20, 20)
    assert {round(x) for x in ito.local_poses.values_list("x", flat=True)} == set(range(1100, 1120))
