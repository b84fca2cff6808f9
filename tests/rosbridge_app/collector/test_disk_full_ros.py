"""Issue 32 over DDS: a full disk during a database outage never stops the recording."""

import time
from pprint import pformat
from urllib.parse import urlsplit, urlunsplit

import pytest

from tests.rosbridge_app.collector.conftest import VEHICLE, logging_robot
from tests.support import diskfull
from tests.support.ros import copy_default_params, requires_ros

pytestmark = [pytest.mark.ros, requires_ros]


def test_a_full_disk_during_an_outage_loses_no_switch_and_the_collector_goes_on(
    ros, procs, robot_leg, ros_env, tmp_path
):
    url = urlsplit(ros_env["FTT_DATABASE_URL"])
    relay = diskfull.Relay((url.hostname or "127.0.0.1", url.port or 5432))
    relay.start()
    netloc = f"{url.username}:{url.password}@127.0.0.1:{relay.port}"
    env = {"FTT_DATABASE_URL": urlunsplit(url._replace(netloc=netloc))}
    params = copy_default_params(tmp_path, vehicle=VEHICLE, **{"spool.disk_headroom_mb": 1})
    try:
        mount = diskfull.small_filesystem(tmp_path / "disk", 4)
        disk = mount.__enter__()
    except Exception:
        pytest.skip("mounting a small file system needs root")
    try:
        collector = procs.start(
            "ftt_collect",
            "--params-file",
            str(params),
            "--name",
            "diskfull",
            "--spool",
            str(disk / "spool.sqlite3"),
            "--start-logging",
            name="diskfull",
            env=env,
        )
        listener = diskfull.Listener(ros.node)
        procs.start(
            "ftt_simulate",
            *diskfull.ROBOT,
            "--switch-every",
            "2",
            "--duration",
            "300",
            name="robot",
        )
        figures = diskfull.run(
            relay=relay,
            leg=robot_leg,
            name="diskfull",
            log=collector.log,
            listener=listener,
            full_seconds=4,
            after_seconds=2,
            alive=collector.alive,
            say=lambda line: None,
        )
        output = collector.output()
        started = time.monotonic()
        collector.stop()
        stopping = time.monotonic() - started
    finally:
        relay.cut()
        procs.stop_all()
        mount.__exit__(None, None, None)
    assert not figures["collector exited"], output
    # In full: pytest shortens a dict shown as the message.
    shown = pformat(figures)
    assert figures["switches while the disk was full"] >= 1, shown
    assert figures["switches published"] >= 5 and figures["switches lost"] == 0, shown
    assert figures["live stored after"] < 2.0, shown
    # Positions cover the whole run, thinned where the disk was full.
    assert figures["largest gap between stored positions"] < 1.5, shown
    assert any(s.startswith("robot disk full since") for s in figures["cockpit showed"])
    assert output.count("robot disk full (") == 1 and "Traceback" not in output, output
    assert stopping < 15


def test_a_full_disk_while_the_database_answers_keeps_every_position_and_camera_frame(
    ros, start_collector, robot_leg
):
    """Nothing needs the disk while the database answers: a robot whose disk is
    full (less free than spool.disk_headroom_mb) still has its track stored at
    the rate it drives, not thinned to the report's resolution, and the camera
    frames before a mode switch stored with the switch."""
    from sensor_msgs.msg import Image, NavSatFix
    from std_msgs.msg import Bool

    from events.models import Segment
    from telemetry.models import Image as StoredImage
    from telemetry.models import Pose
    from tests.support.ros import wait_for

    sent = 30  # 3 s at 10 Hz
    # More headroom than any test machine has free: the disk is full.
    params = {
        "spool.disk_headroom_mb": 1_000_000,
        "params.image_buffer_size": 3,
        "params.image_buffer_step": 0.2,
    }
    collector, fixes, master = logging_robot(
        ros, start_collector, robot_leg, sent, params, auto=True
    )
    assert "robot disk full (" in collector.output()
    camera = ros.publisher(Image, "/image", sent)
    mode = ros.publisher(Bool, "/robot_mode")
    for publisher in (camera, mode):
        ros.wait_subscribed(publisher)
    fix = NavSatFix()
    frame = Image(height=48, width=64, encoding="rgb8", step=64 * 3, data=bytes(48 * 64 * 3))
    for i in range(sent):
        t = time.time()
        fix.header.stamp.sec, fix.header.stamp.nanosec = int(t), int(t % 1 * 1e9)
        frame.header.stamp = fix.header.stamp
        fix.latitude, fix.longitude = 50.6 + i * 1e-5, 7.1
        fixes.publish(fix)
        camera.publish(frame)
        time.sleep(0.1)  # the robot's rate
    stored = Pose.objects.filter(segment=master)
    wait_for(lambda: stored.count() >= sent, 10, what=f"{sent} stored fixes")
    points = stored.values_list("point", flat=True)
    assert sorted(round((p.y - 50.6) * 1e5) for p in points) == list(range(sent))
    mode.publish(Bool(data=False))  # the take-over: the buffered frames go with it
    ito = wait_for(
        lambda: Segment.objects.filter(leg=robot_leg, parent=None, segment_type_id="ito").first(),
        what="the ITO master",
    )
    frames = StoredImage.objects.filter(segment=ito)
    wait_for(lambda: frames.count() >= 3, 10, what="the three frames before the take-over")
    assert frames.count() == 3
