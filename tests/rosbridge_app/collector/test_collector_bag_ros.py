"""The fkie field test bag, replayed into live topics, through a real collector."""

import pytest

from events.models import Segment
from telemetry.models import Pose
from tests.support.fkie import FKIE_BAG, full_rate_length, master_path_length
from tests.support.ros import requires_ros, wait_for

pytestmark = [
    pytest.mark.ros,
    requires_ros,
    pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available"),
]
RATE = 8


def test_fkie_bag_replay_gives_the_recorded_mode_sequence(procs, start_collector, robot_leg):
    collector = start_collector(
        params={"params.robot_mode_type": "industrial"}, args=["--start-logging"]
    )
    player = procs.start(
        "ftt_play_bag",
        str(FKIE_BAG),
        "--rate",
        str(RATE),
        "--wait-for",
        "/robot_mode",
        "/gps_fix",
        name="player",
    )
    wait_for(lambda: player.popen.poll() is not None, 219 / RATE + 40, 0.5, "the bag to end")
    assert player.popen.returncode == 0, player.output()
    previous = [-1]

    def settled():
        count = Pose.objects.count()
        done = count == previous[0]
        previous[0] = count
        return done

    wait_for(settled, 20, 1.0, "the last poses")
    assert collector.stop() == 0, collector.output()

    masters = list(Segment.objects.filter(leg=robot_leg, parent__isnull=True).order_by("start"))
    # Played live, the recording's mode publisher is connected from the start and
    # silent for its first 4.1 s: they have no known mode (collector/unknown_mode.py).
    unknown, *masters = masters
    assert unknown.segment_type_id == "unknown"
    assert [m.segment_type_id for m in masters] == ["ito", "auto", "ito", "auto", "ito"]
    assert (masters[0].start - unknown.start).total_seconds() == pytest.approx(4.1 / RATE, abs=0.2)
    for m in masters:
        reasons = list(m.children.values_list("ito_reason_id", flat=True))
        assert reasons == (["unassigned"] if m.segment_type_id == "ito" else [])
    recorded = sum(master_path_length(m) for m in masters)
    full = full_rate_length()
    assert abs(recorded - full) / full < 0.01, (recorded, full)
    assert recorded == pytest.approx(224, rel=0.01)
    assert Pose.objects.count() < 1000  # thinned from ~21 700 fixes
