"""Storing what the robot measured.

Every row carries the uid the sender gave it, so a sender that retries after
a lost answer (the collector's offline queue, an import run twice) writes each
point once.  Track points and images always belong to a master segment.
"""

import hashlib
import math
import os
import uuid
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from django.contrib.gis.geos import Point
from django.core.files import File
from django.core.files.base import ContentFile
from django.db import connection, transaction
from django.utils import timezone
from psycopg.types.json import Jsonb

from common.errors import RuleViolation
from common.sql import bound_cursor
from events import feed, notifier, rules
from events.feed import announce_row, announce_track, announced
from events.models import Announcement, Leg, PoseSource, Segment, Shift
from events.selectors.segments import pose_target
from events.services.segments import GpsPosition
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.models.poses import FixStatus
from telemetry.pictures import MAP_FORMATS, checked_picture


def master_of(segment: Segment) -> Segment:
    """Data sent for an ITO reason (child) is stored on its master.

    A segment fetched with ``select_related("parent")`` (the API does) costs no query.
    """
    if segment.parent_id is None:
        return segment
    return segment.parent


# FixStatus.values builds a new list on every access; this check runs per pose.
_FIX_STATUSES = frozenset(FixStatus.values)


@dataclass
class GpsFix:
    longitude: float
    latitude: float
    altitude: float | None = None
    fix_status: int = FixStatus.FIX
    horizontal_accuracy: float | None = None
    robot_stamp: datetime | None = None
    uid: uuid.UUID = field(default_factory=uuid.uuid4)

    def check(self) -> None:
        """The rules every stored fix satisfies, whichever way it is stored."""
        GpsPosition(self.longitude, self.latitude)
        for name in ("altitude", "horizontal_accuracy"):
            value = getattr(self, name)
            if value is not None and not math.isfinite(value):
                raise RuleViolation({name: [f"{name.replace('_', ' ')} must be a finite number."]})
        if self.fix_status not in _FIX_STATUSES:
            raise RuleViolation({"fix_status": [f"Unknown fix status {self.fix_status}."]})

    def to_pose(self, segment: Segment, source: PoseSource | None, received) -> Pose:
        """The checked, unsaved row (the archive import inserts these itself)."""
        self.check()
        return self.row(segment, source.pk if source is not None else None, received)

    def row(self, segment: Segment, source_id: int | None, received) -> Pose:
        return Pose(
            uid=self.uid,
            segment=segment,
            point=Point(self.longitude, self.latitude, srid=4326),
            altitude=self.altitude,
            fix_status=self.fix_status,
            horizontal_accuracy=self.horizontal_accuracy,
            pose_source_id=source_id,
            robot_stamp=self.robot_stamp,
            received=received,
        )


@dataclass
class MapPose:
    x: float
    y: float
    frame: str
    yaw: float | None = None
    robot_stamp: datetime | None = None
    uid: uuid.UUID = field(default_factory=uuid.uuid4)

    def check(self) -> None:
        for name in ("x", "y", "yaw"):
            value = getattr(self, name)
            if value is not None and not math.isfinite(value):
                raise RuleViolation({name: [f"{name} must be a finite number."]})
        if not self.frame:
            raise RuleViolation({"frame": ["A local pose needs the name of its map frame."]})

    def to_local_pose(self, segment: Segment, received) -> LocalPose:
        self.check()
        return LocalPose(
            uid=self.uid,
            segment=segment,
            frame=self.frame,
            x=self.x,
            y=self.y,
            yaw=self.yaw,
            robot_stamp=self.robot_stamp,
            received=received,
        )


def record_poses(
    segment: Segment, fixes: list[GpsFix], pose_source: PoseSource | None = None
) -> int:
    """Store GPS fixes on the segment's master; returns how many were new."""
    return len(store_poses(segment, fixes, pose_source))


@transaction.atomic
def store_poses(
    segment: Segment, fixes: list[GpsFix], pose_source: PoseSource | None = None
) -> set[uuid.UUID]:
    """Store GPS fixes on the segment's master; returns the uids of the new rows
    (known uids are skipped, so a retried batch stores nothing twice)."""
    for fix in fixes:
        fix.check()
    if not fixes:
        return set()
    master, source_id = _destination(segment, pose_source)
    return _store_fixes(master, source_id, fixes, timezone.now())


def record_pose(
    segment: Segment, fix: GpsFix, pose_source: PoseSource | None = None
) -> tuple[Pose, bool]:
    """One fix and its row (the API answers with it); a known uid gives the row stored
    first and False."""
    fix.check()
    if connection.vendor == "postgresql":
        stored = record_pose_at(segment.pk, fix, pose_source.pk if pose_source else None)
        if stored is None:
            raise RuleViolation({"segment": ["The segment has just been deleted."]})
        return stored
    with transaction.atomic():
        master, source_id = _destination(segment, pose_source)
        row = fix.row(master, source_id, timezone.now())
        if not _insert_new(Pose, [row]):
            return Pose.objects.get(uid=fix.uid), False
        announce_track(master, [(fix.longitude, fix.latitude)], local=False)
        return row, True


# A single pose on PostgreSQL: one statement, so one round trip and its own
# transaction.  It checks that the segment still exists (the master comes
# from a per-process cache) and that a named pose source does, takes the
# leg's default source as it is now, and adds the feed row only when the pose
# is new.  It tells the feed's trigger not to NOTIFY (notifier.LATER): commits
# that notify cannot share a WAL flush, so its process sends one NOTIFY for
# many poses after their commits (notifier.notify_soon).
_ONE_POSE = f"""
WITH target AS (
    SELECT l.default_pose_source_id AS source, {notifier.LATER}
    FROM {Segment._meta.db_table} m JOIN {Leg._meta.db_table} l
         ON l.id = m.leg_id
    WHERE m.id = %(master)s::bigint
      AND (%(source)s::bigint IS NULL
           OR EXISTS (SELECT 1 FROM {PoseSource._meta.db_table} WHERE id = %(source)s::bigint))
), pose AS (
    INSERT INTO {Pose._meta.db_table} (uid, segment_id, point, altitude, fix_status,
                                       horizontal_accuracy, pose_source_id, robot_stamp, received)
    SELECT %(uid)s::uuid, %(master)s::bigint,
           ST_SetSRID(ST_MakePoint(%(x)s::float8, %(y)s::float8), 4326), %(altitude)s::float8,
           %(fix)s::int2, %(accuracy)s::float8, coalesce(%(source)s::bigint, target.source),
           %(stamp)s::timestamptz, %(received)s::timestamptz
    FROM target
    ON CONFLICT (uid) DO NOTHING
    RETURNING id, pose_source_id
), announced AS (
    INSERT INTO {Announcement._meta.db_table} (kind, created, collector_id, leg_id, payload)
    SELECT %(kind)s::text, %(created)s::timestamptz, NULL, %(leg)s::bigint, %(payload)s::jsonb
    FROM pose
    RETURNING id
)
SELECT (SELECT count(*) FROM target), pose.id, pose.pose_source_id, announced.id
FROM (SELECT 1) AS one LEFT JOIN pose ON true LEFT JOIN announced ON true
"""


def record_pose_at(
    segment_id: int, fix: GpsFix, pose_source_id: int | None = None, *, writer=None
) -> tuple[Pose, bool] | None:
    """:func:`record_pose` for ids as a client sent them, on PostgreSQL in one round
    trip once the segment is known to this process.  None when that is not the
    whole answer (another database, an unknown segment or pose source, a segment
    the ``writer`` may not reach): the caller then checks the ids in full and
    calls :func:`record_pose`, which gives the usual answers."""
    if connection.vendor != "postgresql":
        return None
    master = pose_target(segment_id)
    if master is None or (writer is not None and not rules.may_reach(writer, master)):
        return None
    fix.check()
    received = timezone.now()
    event = feed.track_announcement(master, [(fix.longitude, fix.latitude)], local=False)
    with bound_cursor() as cursor:
        cursor.execute(
            _ONE_POSE,
            {
                "master": master.pk,
                "source": pose_source_id,
                "uid": _as_uuid(fix.uid),
                "x": float(fix.longitude),
                "y": float(fix.latitude),
                "altitude": fix.altitude,
                "fix": int(fix.fix_status),
                "accuracy": fix.horizontal_accuracy,
                "stamp": fix.robot_stamp,
                "received": received,
                "kind": event.kind,
                "created": event.created,
                "leg": event.leg_id,
                "payload": Jsonb(event.payload),
            },
        )
        found, pk, source_id, event_id = cursor.fetchone()
    if not found:
        return None
    if pk is None:
        return Pose.objects.get(uid=fix.uid), False
    feed.inserted(event, event_id)
    # At once in autocommit; after the commit inside a transaction.
    transaction.on_commit(notifier.notify_soon)
    row = fix.row(master, source_id, received)
    row.pk = pk
    return row, True


def _destination(segment: Segment, pose_source: PoseSource | None) -> tuple[Segment, int | None]:
    """The master and the pose source id a fix is stored with.  A segment fetched with
    ``select_related("parent__leg__shift", "leg__shift")`` (the API does) costs no query."""
    master = master_of(segment)
    if pose_source is not None:
        return master, pose_source.pk
    return master, master.leg.default_pose_source_id


def _store_fixes(master, source_id, fixes, received) -> set[uuid.UUID]:
    if connection.vendor == "postgresql":
        new = _insert_fixes_postgres(master, fixes, source_id, received)
    else:
        rows = [fix.row(master, source_id, received) for fix in fixes]
        new = {row.uid for row in _insert_new(Pose, rows)}
    points = [(f.longitude, f.latitude) for f in fixes if _as_uuid(f.uid) in new]
    announce_track(master, points, local=False)
    return new


# One statement with one array per column: its cost does not grow with the
# batch on the client side (no per-row SQL text, no per-row geometry object),
# and ON CONFLICT makes a concurrent retry of the same uid a no-op, not an error.
# The arrays travel as binary parameters (%b): psycopg packs a list of floats,
# uuids or datetimes in C, about three times faster than writing each element
# as text, which was most of the client's time for a big batch.
_POSTGRES_INSERT = """
INSERT INTO {table} (uid, segment_id, point, altitude, fix_status, horizontal_accuracy,
                     pose_source_id, robot_stamp, received)
SELECT u, %b, ST_SetSRID(ST_MakePoint(x, y), 4326), a, f, h, %b, r, %b
FROM unnest(%b::uuid[], %b::float8[], %b::float8[], %b::float8[], %b::int2[],
            %b::float8[], %b::timestamptz[]) AS t(u, x, y, a, f, h, r)
ON CONFLICT (uid) DO NOTHING
RETURNING uid
"""


def _floats(values) -> list[float | None]:
    # psycopg picks one binary type per list from its elements: a fix given as
    # whole degrees (an int) beside fractional ones must not make it an int list.
    return [None if v is None else float(v) for v in values]


def _insert_fixes_postgres(master, fixes, source_id, received) -> set[uuid.UUID]:
    columns = (
        [_as_uuid(f.uid) for f in fixes],
        _floats(f.longitude for f in fixes),
        _floats(f.latitude for f in fixes),
        _floats(f.altitude for f in fixes),
        [int(f.fix_status) for f in fixes],
        _floats(f.horizontal_accuracy for f in fixes),
        [f.robot_stamp for f in fixes],
    )
    insert = _POSTGRES_INSERT.format(table=Pose._meta.db_table)
    return _insert_columns(_POSE_STAGING, insert, columns, [master.pk, source_id, received])


def _insert_columns(staging, insert: str, columns, params) -> set[uuid.UUID]:
    """Store the rows given as column lists (the uid's first, in the staging
    table's order) whose uid is new; returns their uids.  ``params`` come before
    the columns in ``insert`` and are the staging insert's own parameters."""
    if len(columns[0]) >= COPY_FROM:
        return _copy_new(staging, zip(*columns, strict=True), params)
    with bound_cursor() as cursor:
        cursor.execute(insert, [*params, *columns])
        return {_as_uuid(row[0]) for row in cursor.fetchall()}


# From this many rows on, a batch goes to PostgreSQL by COPY into a temporary
# table and one INSERT ... SELECT from there: a third less time than one
# INSERT of unnested arrays for 5 000 poses, in the server (COPY parses rows
# cheaper) and in the client (psycopg writes binary rows in C).  Below it the
# two extra round trips (the table, the COPY) cost more than they save.
COPY_FROM = 100


@dataclass(frozen=True)
class _Staging:
    """A temporary table that a batch is copied into, and the statement that moves
    its rows into the real table.  The retry rule needs ON CONFLICT, which COPY
    lacks; the statement empties the table, so a batch after another in the same
    transaction (an importer's) finds it empty, and ON COMMIT DELETE ROWS gives
    the space back (autovacuum never visits temporary tables)."""

    name: str
    columns: str
    types: tuple[str, ...]
    insert: str

    def create(self) -> str:
        # Per database session; a rolled-back transaction takes it along, so it
        # is asked for every time (one cheap round trip per batch).
        return (
            f"CREATE TEMPORARY TABLE IF NOT EXISTS {self.name} ({self.columns}) "
            "ON COMMIT DELETE ROWS"
        )


_POSE_STAGING = _Staging(
    "ftt_pose_in",
    "u uuid, x float8, y float8, a float8, f int2, h float8, r timestamptz",
    ("uuid", "float8", "float8", "float8", "int2", "float8", "timestamptz"),
    f"""
WITH moved AS (DELETE FROM ftt_pose_in RETURNING *)
INSERT INTO {Pose._meta.db_table} (uid, segment_id, point, altitude, fix_status,
                                   horizontal_accuracy, pose_source_id, robot_stamp, received)
SELECT u, %s, ST_SetSRID(ST_MakePoint(x, y), 4326), a, f, h, %s, r, %s FROM moved
ON CONFLICT (uid) DO NOTHING
RETURNING uid
""",
)

_LOCAL_POSE_STAGING = _Staging(
    "ftt_local_pose_in",
    "u uuid, frame text, x float8, y float8, yaw float8, r timestamptz",
    ("uuid", "text", "float8", "float8", "float8", "timestamptz"),
    f"""
WITH moved AS (DELETE FROM ftt_local_pose_in RETURNING *)
INSERT INTO {LocalPose._meta.db_table} (uid, segment_id, frame, x, y, yaw, robot_stamp, received)
SELECT u, %s, frame, x, y, yaw, r, %s FROM moved
ON CONFLICT (uid) DO NOTHING
RETURNING uid
""",
)


def _copy_new(staging: _Staging, rows, params) -> set[uuid.UUID]:
    """Copy ``rows`` (tuples in the staging table's column order) and store those
    whose uid is new; returns their uids."""
    with bound_cursor() as cursor:
        cursor.execute(staging.create())
        with cursor.copy(f"COPY {staging.name} FROM STDIN (FORMAT BINARY)") as copy:
            copy.set_types(staging.types)
            for row in rows:
                copy.write_row(row)
        cursor.execute(staging.insert, params)
        return {_as_uuid(uid) for (uid,) in cursor.fetchall()}


def _as_uuid(value) -> uuid.UUID:
    # psycopg 3 returns UUID objects, psycopg2 strings.
    return value if isinstance(value, uuid.UUID) else uuid.UUID(value)


@transaction.atomic
def record_local_poses(segment: Segment, poses: list[MapPose]) -> int:
    master = master_of(segment)
    now = timezone.now()
    if connection.vendor == "postgresql" and poses:
        fresh = _insert_local_postgres(master, poses, now)
    else:
        fresh = _insert_new(LocalPose, [pose.to_local_pose(master, now) for pose in poses])
    announce_track(master, [(p.x, p.y) for p in fresh], local=True)
    return len(fresh)


# As for fixes: one statement of column arrays instead of a known-uid query and
# an ORM bulk insert (a replayed outage spool is two thirds local poses).
_POSTGRES_LOCAL_INSERT = """
INSERT INTO {table} (uid, segment_id, frame, x, y, yaw, robot_stamp, received)
SELECT u, %b, f, x, y, w, r, %b
FROM unnest(%b::uuid[], %b::text[], %b::float8[], %b::float8[], %b::float8[],
            %b::timestamptz[]) AS t(u, f, x, y, w, r)
ON CONFLICT (uid) DO NOTHING
RETURNING uid
"""


def _insert_local_postgres(master, poses: list[MapPose], received) -> list[MapPose]:
    for pose in poses:
        pose.check()
    uids = [_as_uuid(p.uid) for p in poses]
    columns = (
        uids,
        [p.frame for p in poses],
        _floats(p.x for p in poses),
        _floats(p.y for p in poses),
        _floats(p.yaw for p in poses),
        [p.robot_stamp for p in poses],
    )
    insert = _POSTGRES_LOCAL_INSERT.format(table=LocalPose._meta.db_table)
    new = _insert_columns(_LOCAL_POSE_STAGING, insert, columns, [master.pk, received])
    return [p for p, uid in zip(poses, uids, strict=True) if uid in new]


def _insert_new(model, rows) -> list:
    """The rows whose uid is not stored yet, inserted (with their ids set)."""
    if not rows:
        return []
    known = set(model.objects.filter(uid__in=[r.uid for r in rows]).values_list("uid", flat=True))
    fresh = [r for r in rows if r.uid not in known]
    model.objects.bulk_create(fresh, batch_size=1000)
    return fresh


def check_map_placement(*, width, height, resolution, origin_x, origin_y, origin_yaw) -> None:
    """What every stored map must satisfy, whoever stores it (collector, API, import)."""
    for name, value in (
        ("resolution", resolution),
        ("origin_x", origin_x),
        ("origin_y", origin_y),
        ("origin_yaw", origin_yaw),
    ):
        if not isinstance(value, int | float) or not math.isfinite(value):
            raise RuleViolation({name: ["Must be a finite number."]})
    if resolution <= 0 or width <= 0 or height <= 0:
        raise RuleViolation("A map needs a positive size and resolution.")


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


def record_map(shift: Shift, **fields) -> tuple[MapImage, bool]:
    """Store a map (the fields of :class:`MapPicture`) for the shift unless it equals
    the newest one; returns (map, stored)."""
    return record_maps(shift, [MapPicture(**fields)])[0]


@transaction.atomic
def record_maps(shift: Shift, maps: list[MapPicture]) -> list[tuple[MapImage, bool]]:
    """Store maps in order, each unless it equals the newest one before it (a known
    uid gives the map stored first); returns (map, stored) for each.

    A replayed collector spool holds a map every few seconds: the maps of a batch
    share the lock, the queries and one insert, and only the newest one stored is
    announced (a browser shows the current map, never the ones in between)."""
    for m in maps:
        m.uid = _as_uuid(m.uid) if m.uid is not None else None
    uids = [m.uid for m in maps if m.uid is not None]
    known = {row.uid: row for row in MapImage.objects.filter(uid__in=uids)} if uids else {}
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
        announced(fresh[-1])
    return results


@transaction.atomic
def attach_image(
    segment: Segment,
    *,
    content: bytes,
    description: str = "",
    robot_stamp: datetime | None = None,
    uid: uuid.UUID | None = None,
) -> Image:
    """Store a camera frame or an uploaded photo on the segment's master."""
    if uid is not None and (existing := Image.objects.filter(uid=uid).first()):
        return existing
    if not content:
        raise RuleViolation({"image": ["The image is empty."]})
    suffix = checked_picture(content)
    image = Image(segment=master_of(segment), description=description, robot_stamp=robot_stamp)
    if uid is not None:
        image.uid = uid
    image.image.save(f"image.{suffix}", ContentFile(content), save=False)
    image.save()
    return announced(image)


def attach_recording(
    segment: Segment,
    *,
    path: Path,
    start: datetime,
    end: datetime,
    topics: dict,
    reason: str = "",
    uid: uuid.UUID | None = None,
) -> Recording:
    """Store a black-box MCAP file on the segment's master; ``path`` stays as it
    is (the caller removes it once this is committed)."""
    if uid is not None and (existing := Recording.objects.filter(uid=uid).first()):
        return existing
    if end < start:
        raise RuleViolation({"end": ["The window ends before it starts."]})
    path = Path(path)
    recording = Recording(
        segment=master_of(segment),
        start=start,
        end=end,
        topics=topics,
        message_count=sum(int(t.get("count", 0)) for t in topics.values()),
        size=path.stat().st_size,
        reason=reason,
    )
    if uid is not None:
        recording.uid = uid
    _store_file(recording, path)
    recording.save()
    return announced(recording)


class _SecondName(File):
    """A hard link to a file, which the storage moves in: a rename when the media
    directory is on the same filesystem, a copy otherwise (Django's
    ``file_move_safe``)."""

    def temporary_file_path(self) -> str:
        return self.name


def _store_file(recording: Recording, path: Path) -> None:
    """Put the file into media storage without copying it where possible: the
    collector stores a 12 MB snapshot in the same transaction as the mode and
    pose rows behind it, and a copy took 20-40 ms of it."""
    link = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.link")
    try:
        os.link(path, link)
    except OSError:  # no hard links there (another kind of filesystem)
        with path.open("rb") as f:
            recording.file.save(path.name, File(f), save=False)
        return
    try:
        recording.file.save(path.name, _SecondName(None, str(link)), save=False)
    finally:
        link.unlink(missing_ok=True)  # left only if the storage failed


@transaction.atomic
def delete_image(image: Image) -> None:
    announce_row(image, deleted=True)
    image.delete()


@transaction.atomic
def delete_recording(recording: Recording) -> None:
    announce_row(recording, deleted=True)
    recording.delete()
