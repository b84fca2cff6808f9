"""ftt_import_bag --snapshots cuts the black box's windows out of a recording."""

import io
from datetime import timedelta

import pytest
from django.core.management import call_command

from events.models import Segment, Vehicle
from rosbridge_app.collector.bag import bag_messages
from telemetry.models import Recording
from tests.support.fkie import FKIE_BAG
from tests.support.mcap_files import read_mcap

pytestmark = [
    pytest.mark.django_db,
    pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available"),
]


def test_every_take_over_of_the_bag_gets_its_window_as_mcap(vehicle, media_root):
    call_command(
        "ftt_import_bag",
        str(FKIE_BAG),
        "--vehicle",
        "husky",
        "--snapshots",
        "--snapshot",
        "before=5",
        "--snapshot",
        "after=2",
        stdout=io.StringIO(),
        stderr=io.StringIO(),
    )
    itos = list(Segment.objects.filter(parent=None, segment_type_id="ito").order_by("start"))
    assert len(itos) == 3
    fixes = [(m.time_ns, m.msg.latitude) for m in bag_messages(FKIE_BAG, {"/gps_fix"})]
    for ito in itos:
        (recording,) = Recording.objects.filter(segment=ito)
        assert recording.start == ito.start - timedelta(seconds=5)
        assert recording.end == ito.start + timedelta(seconds=2)
        back = read_mcap(recording.file.path)
        lo, hi = (t.timestamp() * 1e9 for t in (recording.start, recording.end))
        expected = [lat for t, lat in fixes if lo <= t <= hi]
        got = [m.latitude for topic, _, m in back["messages"] if topic == "/gps_fix"]
        assert got == expected and len(got) > 100
        # The first ITO starts at the bag's first fix, 4.1 s before the robot first says
        # its mode (collector/unknown_mode.py): its window ends before that message.
        said = [] if ito == itos[0] else [1]
        assert [m.val for topic, _, m in back["messages"] if topic == "/robot_mode"] == said
        if said:
            assert "int8 MANUAL" in back["schemas"]["industrial_msgs/msg/RobotMode"]
    # A snapshot is a recording of its own: the last one imported back, as it was
    # downloaded (a bare .mcap file), is one take-over from its first fix (the mode
    # said within params.unknown_mode_wait of it, collector/unknown_mode.py).
    snapshot = Recording.objects.get(segment=itos[-1])
    messages = read_mcap(snapshot.file.path)["messages"]
    first_fix_ns = min(t for topic, t, _ in messages if topic == "/gps_fix")
    Vehicle.objects.create(key="replay", short_description="Replay", institution="FKIE")
    call_command(
        "ftt_import_bag",
        snapshot.file.path,
        "--vehicle",
        "replay",
        stdout=io.StringIO(),
        stderr=io.StringIO(),
    )
    (replayed,) = Segment.objects.filter(parent=None, leg__shift__vehicle__key="replay")
    assert replayed.segment_type_id == "ito"
    assert replayed.start.timestamp() * 1e9 == pytest.approx(first_fix_ns, abs=1e3)
    assert replayed.poses.count() > 0
