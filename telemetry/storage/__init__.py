"""The storage port: the only code that knows how robot data lies in the database.

Services keep the rules (what is stored, the figures' arithmetic) and
selectors the shapes (tracks, distances); they call the operations below, and
nothing above this package asks which database it runs on.  ``keys`` states
the driving order, what a usable fix is and the column lists; ``rows`` what
the operations hand back.  The adapter of the connection's database does the
work: ``postgresql`` (month partitions, binary arrays, COPY, packed reads) or
``spatialite`` (one table, the ORM).  Both skip a known uid (a retry is
stored once): the same ``ON CONFLICT DO NOTHING`` statement for one pose, and
for a batch ``ON CONFLICT`` on PostgreSQL and a look-up under the write lock
on SpatiaLite.  tests/telemetry/storage/test_contract.py states each
operation for both adapters.
"""

from types import ModuleType

from django.db import connection

from telemetry.storage import postgresql, spatialite
from telemetry.storage.rows import Change, NewPoint, StoredFigures

__all__ = [
    "Change", "StoredFigures", "NewPoint", "adapter", "insert_fixes", "insert_local_poses",
    "insert_pose", "is_partitioned", "locked_figures", "neighbours", "plain_rows", "points_between",
    "read_stored_figures", "track_arrays", "write_change",
]  # fmt: skip

ADAPTERS = {module.NAME: module for module in (postgresql, spatialite)}


def adapter() -> ModuleType:
    """The adapter of the database Django's connection uses."""
    return ADAPTERS[connection.vendor]


def insert_pose(
    master_id: int, fix, source_id: int | None, received, refused_by=None
) -> tuple | None:
    """Store one checked fix on the master segment ``master_id``: (the new row's
    id, what its segment's figures held, ``StoredFigures`` or None), or None when
    nothing was stored (a known uid, the segment or pose source no longer
    exists, or the queryset ``refused_by`` finds a row: a rule the caller
    states, checked in the same statement)."""
    return adapter().insert_pose(master_id, fix, source_id, received, refused_by)


def insert_fixes(master, source_id: int | None, fixes, received, refused_by=None) -> list[NewPoint]:
    """Store checked fixes on ``master``, each uid once; the new rows.  Nothing
    is stored while the queryset ``refused_by`` finds a row (a rule the caller
    states, checked in the insert's statement where the database allows)."""
    return adapter().insert_fixes(master, source_id, fixes, received, refused_by)


def insert_local_poses(master, poses, received) -> list[NewPoint]:
    """Store checked map-frame poses on ``master``, each uid once; the new rows."""
    return adapter().insert_local_poses(master, poses, received)


def read_stored_figures(master_id: int, mode: str) -> StoredFigures | None:
    """What the segment's figures row of ``mode`` holds, or None without one."""
    return adapter().read_stored_figures(master_id, mode)


def locked_figures(master_id: int, mode: str):
    """The segment's figures row of ``mode`` (made empty when it has none),
    locked until the transaction ends."""
    return adapter().locked_figures(master_id, mode)


def write_change(
    master_id: int, mode: str, seen: StoredFigures | None, change: Change, feed_row=None
) -> tuple[bool, StoredFigures | None]:
    """Add ``change`` to the figures row if it still holds ``seen`` (or, for
    None, does not exist yet): (True, None) when it did, else (False, what the
    row holds now).  When it did not, the row is locked until the transaction
    ends (an upsert locks the row it finds), so what it holds now is what the
    next ``write_change`` finds.  ``feed_row`` (an unsaved change-feed row) is
    inserted in the same statement where the database allows (PostgreSQL; its
    pk is set then) and only when the change applied; else it stays unsaved
    for the caller (events.feed.settle)."""
    return adapter().write_change(master_id, mode, seen, change, feed_row)


def neighbours(master_id: int, mode: str, first: tuple, last: tuple) -> tuple:
    """(the usable point before ``first``, the one after ``last``) in driving
    order, each (id, x, y) or None; ``first``/``last`` are driving-order keys
    (robot stamp, arrival, id)."""
    return adapter().neighbours(master_id, mode, first, last)


def points_between(master_id: int, mode: str, first: tuple, last: tuple) -> list[tuple]:
    """The usable points from ``first`` to ``last`` (both included) in driving
    order, as (id, x, y)."""
    return adapter().points_between(master_id, mode, first, last)


def track_arrays(segment_ids, mode: str, figures_mode: str | None):
    """(segment id, x, y, seconds since 1970, extra) of each segment that has
    points of ``mode``, its usable points in driving order; ``extra`` is the
    count of fixes without a position (GPS) or the frame of the first point
    (local).  A ``figures_mode`` bounds the read by the span the segments' kept
    figures of that mode give (PostgreSQL reads only the months they span);
    None reads every pose, for measuring the figures themselves."""
    return adapter().track_arrays(segment_ids, mode, figures_mode)


def plain_rows(queryset) -> list[tuple]:
    """The rows of a ``values_list`` queryset of plain columns (numbers, text,
    timestamps), as ``list(queryset)`` gives them, read the fastest way the
    database offers."""
    if queryset.query.annotation_select:
        raise ValueError("plain_rows reads columns, not annotations")
    return adapter().plain_rows(queryset)


def is_partitioned(table: str) -> bool:
    """Whether a pose table is partitioned by month (never on SpatiaLite)."""
    return adapter().is_partitioned(table)
