"""The driving order of a segment's points, for the ORM and for hand-written SQL.

Points are ordered by the robot's clock (points without one last), then by
arrival, then by id, so a late-arriving batch from the collector's spool still
lands where it was driven.  These are the keys of the pose_segment_time and
localpose_segment_time indexes after the segment, so a track is read without
a sort.
"""

from django.db.models import F, OrderBy

# The first key may be missing (a pose without the robot's clock): it sorts last.
KEYS = ("robot_stamp", "received", "id")


def order_by() -> tuple[OrderBy, ...]:
    """The driving order as ORM expressions, for ``QuerySet.order_by``."""
    first, *rest = KEYS
    return (F(first).asc(nulls_last=True), *(F(key).asc() for key in rest))


def order_sql() -> str:
    """The driving order as an SQL ``ORDER BY`` list of the same keys."""
    first, *rest = KEYS
    return ", ".join([f"{first} ASC NULLS LAST", *rest])
