"""ftt_import_bag on the original FTT's sample recording (ROS 1, and converted to ROS 2)."""

import io
import re
import shutil
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import pytest
from django.core.management import CommandError, call_command

from events.models import Segment, Shift, TestEvent
from events.services import logs
from telemetry.models import Pose
from tests.support.fkie import FKIE_BAG, master_path_length

BAG_START = datetime(2019, 4, 8, 14, 12, 44, tzinfo=UTC)

pytestmark = [
    pytest.mark.django_db,
    pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available"),
]


@pytest.fixture(scope="module")
def ros2_bags(tmp_path_factory):
    convert = Path(sys.executable).with_name("rosbags-convert")
    root = tmp_path_factory.mktemp("bags")
    bags = {"sqlite3": root / "fkie_sqlite3", "mcap": root / "fkie_mcap"}
    subprocess.run(
        [convert, "--src", FKIE_BAG, "--dst", bags["sqlite3"]], check=True, capture_output=True
    )
    subprocess.run(
        [convert, "--src", FKIE_BAG, "--dst", bags["mcap"], "--dst-storage", "mcap",
         "--dst-typestore", "ros2_jazzy"],
        check=True, capture_output=True,
    )  # fmt: skip
    yield bags
    shutil.rmtree(root, ignore_errors=True)


class Terminal(io.StringIO):
    def isatty(self):
        return True


def import_bag(*args, stderr=None) -> str:
    out = io.StringIO()
    call_command("ftt_import_bag", *map(str, args), stdout=out, stderr=stderr or io.StringIO())
    return out.getvalue()


def masters():
    return list(Segment.objects.filter(parent__isnull=True).order_by("start"))


def assert_fkie_result():
    found = masters()
    assert [m.segment_type_id for m in found] == ["ito", "auto", "ito", "auto", "ito"]
    for m in found:
        reasons = list(m.children.values_list("ito_reason_id", flat=True))
        assert reasons == (["unassigned"] if m.segment_type_id == "ito" else [])
    total = sum(master_path_length(m) for m in found)
    assert total == pytest.approx(224, rel=0.01)
    return total


def test_ros1_bag_becomes_a_closed_test_event_with_five_masters(vehicle, media_root):
    terminal = Terminal()
    out = import_bag(FKIE_BAG, "--vehicle", "husky", stderr=terminal)
    assert "5 master segments" in out
    # On a terminal both phases show a bar that ends full: the bag's 22,143
    # routed messages, then the events the collector's code made of them.
    bars = terminal.getvalue()
    assert "Reading messages [" + "#" * 30 + "] 22143/22143" in bars
    assert re.search(r"Storing events +\[#{30}\] (\d+)/\1", bars)
    assert_fkie_result()
    event = TestEvent.objects.get()
    assert event.start.replace(microsecond=0) == BAG_START and event.end is not None
    shift = Shift.objects.get()
    assert (shift.vehicle, shift.number) == (vehicle, 1)
    assert shift.legs.get().recording == "fkie_test.bag"


def test_importing_the_same_bag_again_adds_nothing(vehicle, media_root):
    log = io.StringIO()
    import_bag(FKIE_BAG, "--vehicle", "husky", stderr=log)
    assert "Importing" in log.getvalue() and "[#" not in log.getvalue()  # no bars in a log
    poses, segments = Pose.objects.count(), Segment.objects.count()
    out = import_bag(FKIE_BAG, "--vehicle", "husky")
    assert "added 0 Pose" in out
    assert (Pose.objects.count(), Segment.objects.count()) == (poses, segments)
    assert TestEvent.objects.count() == 1 and segments == 8


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_ros2_conversions_give_the_same_segments(vehicle, media_root, ros2_bags, storage):
    import_bag(ros2_bags[storage], "--vehicle", "husky", "--mode-type", "industrial")
    assert_fkie_result()
    # The same recording as ROS 1 is recognised: nothing is added.
    poses = Pose.objects.count()
    import_bag(FKIE_BAG, "--vehicle", "husky")
    assert Pose.objects.count() == poses


def test_import_into_a_given_open_leg(vehicle, media_root):
    start = datetime(2019, 4, 8, tzinfo=UTC)
    event = logs.create_test_event(at=start)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, at=start)
    leg = logs.create_leg(shift=shift, at=start)
    import_bag(FKIE_BAG, "--vehicle", "husky", "--leg", leg.uid)
    assert_fkie_result()
    assert {m.leg for m in masters()} == {leg}
    leg.refresh_from_db()
    assert leg.end is None  # the user's leg stays as it was


def test_leg_of_another_vehicle_is_refused(vehicle, other_vehicle, media_root):
    start = datetime(2019, 4, 8, tzinfo=UTC)
    shift = logs.create_shift(
        test_event=logs.create_test_event(at=start), vehicle=other_vehicle, at=start
    )
    leg = logs.create_leg(shift=shift, at=start)
    with pytest.raises(CommandError, match="vehicle 'jackal', not 'husky'"):
        import_bag(FKIE_BAG, "--vehicle", "husky", "--leg", leg.pk)
    assert not Segment.objects.exists()


def test_open_shift_of_the_vehicle_is_not_closed_by_a_recording_from_the_past(vehicle, media_root):
    live = logs.create_shift(test_event=logs.create_test_event(), vehicle=vehicle)
    with pytest.raises(CommandError, match="has an open shift"):
        import_bag(FKIE_BAG, "--vehicle", "husky")
    live.refresh_from_db()
    assert live.end is None and not Segment.objects.exists()
