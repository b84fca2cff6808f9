"""How robot data is keyed and ordered, for the ORM and for hand-written SQL.

Driving order: a segment's points are ordered by the robot's clock (points
without one last), then by arrival, then by id, so a late-arriving batch from
the collector's spool still lands where it was driven.  These are the keys of
the pose_segment_time and localpose_segment_time indexes after the segment, so
a track is read without a sort.

A usable fix is a GPS pose that is not flagged "no fix" (such a fix carries
no position); every local pose is usable.  A master segment is one without a
parent: ``Segment.objects.masters()`` (events.models.hierarchy).
"""

from django.db.models import F, OrderBy, Q

from telemetry.models.poses import FixStatus

# The two kinds of track: GPS poses (longitude, latitude) and local poses
# (map-frame metres).  Also the ``mode`` of a segment's stored figures row.
GPS_TRACK = "gps"
LOCAL_TRACK = "local"
TRACK_KINDS = (GPS_TRACK, LOCAL_TRACK)

# The first key may be missing (a pose without the robot's clock): it sorts last.
DRIVING_ORDER = ("robot_stamp", "received", "id")


def order_by() -> tuple[OrderBy, ...]:
    """The driving order as ORM expressions, for ``QuerySet.order_by``."""
    first, *rest = DRIVING_ORDER
    return (F(first).asc(nulls_last=True), *(F(key).asc() for key in rest))


def reverse_order_by() -> tuple[OrderBy, ...]:
    """The driving order backwards (the newest point first)."""
    return tuple(o.copy().reverse_ordering() for o in order_by())


def order_sql() -> str:
    """The driving order as an SQL ``ORDER BY`` list of the same keys."""
    first, *rest = DRIVING_ORDER
    return ", ".join([f"{first} ASC NULLS LAST", *rest])


# A usable fix, for ``QuerySet.filter`` of GPS poses and in SQL.
USABLE_FIX = ~Q(fix_status=FixStatus.NO_FIX)
USABLE_FIX_SQL = f"fix_status <> {int(FixStatus.NO_FIX)}"


def usable(queryset, mode: str):
    """The usable points of a pose ``queryset`` of ``mode``."""
    return queryset.filter(USABLE_FIX) if mode == GPS_TRACK else queryset


# The columns of a GPS pose row and of a local pose row, in the order every
# insert gives them.
POSE_COLUMNS = (
    "uid, segment_id, point, altitude, fix_status, horizontal_accuracy, "
    "pose_source_id, robot_stamp, received"
)
LOCAL_POSE_COLUMNS = "uid, segment_id, frame, x, y, yaw, robot_stamp, received"

# What a writer reads of a segment's figures row (rows.StoredFigures), and the columns
# a change writes.
STORED_FIGURES_COLUMNS = (
    "points", "no_fix", "last_robot_stamp", "last_received", "last_id", "last_x", "last_y",
    "uid_sum",
)  # fmt: skip
FIGURE_FIELDS = (
    "points", "no_fix", "length", "first_x", "first_y", "last_x", "last_y", "last_robot_stamp",
    "last_received", "last_id", "first_stamp", "last_stamp", "min_x", "min_y", "max_x", "max_y",
    "uid_sum",
)  # fmt: skip
