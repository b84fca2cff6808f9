"""What the port's writes and reads hand back, the same from either adapter."""

import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import NamedTuple

from django.utils.dateparse import parse_datetime


class NewPoint(NamedTuple):
    """A point an insert stored, with what its segment's figures need
    (telemetry.services.segment_figures); ``usable``: not a fix without a position."""

    uid: uuid.UUID
    id: int
    robot_stamp: datetime | None
    received: datetime
    x: float
    y: float
    usable: bool


@dataclass(frozen=True)
class StoredFigures:
    """What a writer reads of the figures row: the pose set's version (its
    counts) and the last usable point, the one an appended batch joins."""

    points: int
    no_fix: int
    last_robot_stamp: datetime | None
    last_received: datetime | None
    last_id: int | None
    last_x: float | None
    last_y: float | None
    uid_sum: str


@dataclass(frozen=True)
class Change:
    """What new points change in a segment's figures.  ``alone`` are the
    figures of the new points by themselves (the row of a segment without one);
    ``length`` is what they add to the stored length; ``first``/``last`` say
    whether they become the track's first or last point; ``uid_sum`` is the
    stored uid sum with theirs added."""

    alone: dict
    length: float
    first: bool
    last: bool
    uid_sum: str


def stored_figures_from(values) -> StoredFigures | None:
    """``StoredFigures`` from the values of a figures row's ``keys.STORED_FIGURES_COLUMNS``; None
    when the segment has no figures row yet."""
    if values[0] is None:
        return None
    points, no_fix, robot_stamp, received, last_id, x, y, uids = values
    return StoredFigures(
        points, no_fix, instant(robot_stamp), instant(received), last_id, x, y, uids
    )


def instant(value) -> datetime | None:
    # SpatiaLite gives a subquery's timestamp as Django's naive UTC text.
    if isinstance(value, str):
        value = parse_datetime(value)
    if value is not None and value.tzinfo is None:
        value = value.replace(tzinfo=UTC)
    return value


def as_uuid(value) -> uuid.UUID:
    # psycopg 3 returns UUID objects, psycopg2 strings.
    return value if isinstance(value, uuid.UUID) else uuid.UUID(value)


def floats(values) -> list[float | None]:
    # psycopg picks one binary type per list from its elements: a fix given as
    # whole degrees (an int) beside fractional ones must not make it an int list.
    return [None if v is None else float(v) for v in values]
