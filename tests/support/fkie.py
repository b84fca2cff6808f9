"""The fkie recording and path lengths, measured the way the report measures them."""

from pathlib import Path

from telemetry.selectors.distances import path_length
from telemetry.storage.keys import GPS_TRACK

FKIE_BAG = Path(__file__).resolve().parents[2].parent / "shared" / "fixtures" / "fkie_test.bag"


def gps_path_length(points: list[tuple[float, float]]) -> float:
    """Metres along (longitude, latitude) points."""
    return path_length([p[0] for p in points], [p[1] for p in points], GPS_TRACK)


def master_path_length(master) -> float:
    poses = master.poses.order_by("robot_stamp", "id")
    return gps_path_length([(p.point.x, p.point.y) for p in poses])


def full_rate_length() -> float:
    """Every fix of the bag from the first mode message on (the 416 fixes before it,
    now kept in the first segment, add 0.16 m of GPS noise)."""
    from rosbridge_app.collector.bag import bag_messages

    points, started = [], False
    for m in bag_messages(FKIE_BAG):
        started = started or m.msgtype.endswith("RobotMode")
        if started and m.msgtype.endswith("NavSatFix"):
            points.append((m.msg.longitude, m.msg.latitude))
    return gps_path_length(points)
