"""Storing the robot's maps: where a map lies, and each map unless it equals the
newest one of its shift."""

import hashlib
import math
import uuid
from dataclasses import dataclass
from datetime import datetime

from django.core.files.base import ContentFile
from django.db import transaction
from django.utils.translation import gettext

from common.errors import RuleViolation
from common.retries import stored_rows
from events.feed import announce_and_return
from events.models import Shift
from events.services.finality import require_amendable
from telemetry.models import MapImage
from telemetry.pictures import MAP_FORMATS, checked_picture
from telemetry.storage.rows import as_uuid

# The most cells a map may have along either side.
MAX_MAP_CELLS = 100_000


def check_map_placement(*, width, height, resolution, origin_x, origin_y, origin_yaw) -> None:
    """What every stored map must satisfy, whoever stores it (collector, API, import);
    refuses with a message per field."""
    errors = {}
    for name, value in (("width", width), ("height", height)):
        if not isinstance(value, int) or not 0 < value <= MAX_MAP_CELLS:
            errors[name] = [
                gettext("Must be a whole number of cells from 1 to %(most)s.")
                % {"most": MAX_MAP_CELLS}
            ]
    for name, value in (
        ("resolution", resolution),
        ("origin_x", origin_x),
        ("origin_y", origin_y),
        ("origin_yaw", origin_yaw),
    ):
        if not isinstance(value, int | float) or not math.isfinite(value):
            errors[name] = [gettext("Must be a finite number.")]
    if "resolution" not in errors and resolution <= 0:
        errors["resolution"] = [gettext("Resolution must be positive (metres per cell).")]
    if errors:
        raise RuleViolation(errors)


@dataclass
class MapPicture:
    """A map to store: the PNG and where it lies."""

    png: bytes
    frame: str
    width: int
    height: int
    resolution: float
    origin_x: float
    origin_y: float
    origin_yaw: float = 0.0
    robot_stamp: datetime | None = None
    checksum: str | None = None
    uid: uuid.UUID | None = None

    def placement(self) -> tuple:
        return tuple(getattr(self, name) for name in MapImage.PLACEMENT_FIELDS)


def store_map(shift: Shift, **fields) -> tuple[MapImage, bool]:
    """Store a map (the fields of :class:`MapPicture`) for the shift unless it equals
    the newest one; returns (map, stored)."""
    return store_maps(shift, [MapPicture(**fields)])[0]


@transaction.atomic
def store_maps(shift: Shift, maps: list[MapPicture]) -> list[tuple[MapImage, bool]]:
    """Store maps in order, each unless it equals the newest one before it (a known
    uid gives the map stored first); returns (map, stored) for each.

    A replayed collector spool holds a map every few seconds: the maps of a batch
    share the lock, the queries and one insert, and only the newest one stored is
    announced (a browser shows the current map, never the ones in between)."""
    for m in maps:
        m.uid = as_uuid(m.uid) if m.uid is not None else None
    known = stored_rows(MapImage, [m.uid for m in maps], shift_id=shift.pk)
    if any(m.uid not in known for m in maps):
        require_amendable(pk=shift.test_event_id)
    for m in maps:
        if m.uid in known:
            continue
        check_map_placement(
            width=m.width,
            height=m.height,
            resolution=m.resolution,
            origin_x=m.origin_x,
            origin_y=m.origin_y,
            origin_yaw=m.origin_yaw,
        )
        checked_picture(m.png, MAP_FORMATS)
    Shift.objects.select_for_update().get(pk=shift.pk)
    newest = shift.maps.order_by("-received", "-id").first()
    results, fresh = [], []
    for m in maps:
        if m.uid in known:
            results.append((known[m.uid], False))
            continue
        checksum = m.checksum or hashlib.sha256(m.png).hexdigest()
        if (
            newest is not None
            and newest.checksum == checksum
            and m.placement() == tuple(getattr(newest, f) for f in MapImage.PLACEMENT_FIELDS)
        ):
            results.append((newest, False))
            continue
        newest = MapImage(
            shift=shift,
            **{name: getattr(m, name) for name in MapImage.PLACEMENT_FIELDS},
            checksum=checksum,
            robot_stamp=m.robot_stamp,
        )
        if m.uid is not None:
            newest.uid = m.uid
            known[m.uid] = newest  # the same uid twice in one batch: stored once
        newest.image.save(f"{newest.uid}.png", ContentFile(m.png), save=False)
        fresh.append(newest)
        results.append((newest, True))
    MapImage.objects.bulk_create(fresh)
    if fresh:
        announce_and_return(fresh[-1])
    return results
