"""Importing telemetry: poses and local poses (added, never changed), maps, camera
images and black-box snapshots with their files."""

import uuid
from collections import defaultdict
from itertools import islice
from pathlib import PurePosixPath

from django.core.exceptions import ValidationError
from django.core.files.base import ContentFile
from django.utils.translation import gettext

from events.models import PoseSource, Segment, Shift
from exchange import records as rec
from exchange.importer.plan import MalformedRecord, describe
from exchange.importer.session import ImportSession
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.pictures import MAP_FORMATS, PHOTO_FORMATS, checked_picture
from telemetry.services.map_images import check_map_placement
from telemetry.services.pose_writes import GpsFix, MapPose
from telemetry.services.segment_figures import measure_figures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

BATCH = 2000
# Every MCAP file starts with these bytes (the format's magic).
MCAP_MAGIC = b"\x89MCAP0\r\n"


def _batches(iterable, size):
    iterator = iter(iterable)
    while batch := list(islice(iterator, size)):
        yield batch


def _add_track_points(session: ImportSession, table, model, build):
    for batch in _batches(session.records(table), BATCH):
        uids = [uuid.UUID(r["uid"]) for r in batch]
        by_master = defaultdict(list)
        for uid, r in zip(uids, batch, strict=True):
            session.where = f"{table} record {uid}"
            by_master[session.master(r["segment"]).pk].append(uid)
        known = set()
        for master_id, group in by_master.items():
            known |= session.known(table, model, group, segment_id=master_id)
        fresh = []
        for uid, r in zip(uids, batch, strict=True):
            if uid in known:
                continue
            session.where = f"{table} record {uid}"
            fresh.append(build(uid, r))
            known.add(uid)
        model.objects.bulk_create(fresh, batch_size=BATCH)
        session.plan.note(table, "added", len(fresh))
        for row in fresh:
            session.track_points[(table, row.segment_id)] += 1
        session.plan.note(table, "unchanged", len(batch) - len(fresh))
    # An archive's poses may fall anywhere in a stored track: measure it again.
    mode = GPS_TRACK if model is Pose else LOCAL_TRACK
    measure_figures({seg for kind, seg in session.track_points if kind == table}, [mode])


def import_poses(session: ImportSession):
    def build(uid, r):
        point = r["point"]
        if not isinstance(point, list) or len(point) != 2:
            session.refuse(f"{session.where}: point must be [longitude, latitude].")
        fix = GpsFix(
            longitude=point[0],
            latitude=point[1],
            altitude=r["altitude"],
            fix_status=r["fix_status"],
            horizontal_accuracy=r["horizontal_accuracy"],
            robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
            uid=uid,
        )
        source = session.config_row(
            session.pose_sources, PoseSource, r["pose_source"], "pose source"
        )
        return fix.to_pose(
            session.master(r["segment"]), source, rec.time_in(r["received"], "received")
        )

    _add_track_points(session, "poses", Pose, build)


def import_local_poses(session: ImportSession):
    def build(uid, r):
        pose = MapPose(
            x=r["x"],
            y=r["y"],
            frame=r["frame"],
            yaw=r["yaw"],
            robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
            uid=uid,
        )
        return pose.to_local_pose(
            session.master(r["segment"]), rec.time_in(r["received"], "received")
        )

    _add_track_points(session, "local_poses", LocalPose, build)


def _store_file(session: ImportSession, row, record, formats, field="image"):
    """``formats``: the picture formats allowed, or None for a black-box
    snapshot, which must be an MCAP file."""
    name = record["file"]
    content = session.bundle.read_file(name)
    stored = getattr(row, field)
    # The archive's file name is not trusted: the checked format names the file.
    if formats is None:
        if not content.startswith(MCAP_MAGIC):
            raise MalformedRecord(
                gettext("%(where)s: the snapshot is not an MCAP file.") % {"where": session.where}
            )
        suffix = "mcap"
    else:
        try:
            suffix = checked_picture(content, formats)
        except ValidationError as exc:
            raise MalformedRecord(f"{session.where}: {describe(exc)}") from None
    if session.dry_run:
        stored.name = name
        return
    stored.save(f"{PurePosixPath(name).stem}.{suffix}", ContentFile(content), save=False)
    session.written.append((stored.storage, stored.name))


def _add_with_file(session: ImportSession, table, row, record, formats, field="image", exclude=()):
    _store_file(session, row, record, formats, field)
    row.full_clean(validate_unique=False, exclude=exclude)
    row.save()
    session.plan.note(table, "added")
    session.changed.append(row)


def import_maps(session: ImportSession):
    for r in session.records("maps"):
        uid = uuid.UUID(r["uid"])
        shift_id = session.entry_id(session.shifts, Shift, r["shift"], "shift")
        if session.known("maps", MapImage, [uid], shift_id=shift_id):
            session.plan.note("maps", "unchanged")
            continue
        placement = {name: r[name] for name in MapImage.PLACEMENT_FIELDS if name != "frame"}
        try:
            check_map_placement(**placement)
        except ValidationError as exc:
            session.refuse(f"maps record {uid}: {describe(exc)}")
        row = MapImage(
            uid=uid,
            shift_id=shift_id,
            **{name: r[name] for name in (*MapImage.PLACEMENT_FIELDS, "checksum")},
            robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
            received=rec.time_in(r["received"], "received"),
        )
        _add_with_file(session, "maps", row, r, MAP_FORMATS)


def import_images(session: ImportSession):
    for r in session.records("images"):
        uid = uuid.UUID(r["uid"])
        master = session.master(r["segment"])
        row = session.stored("images", Image, uid, segment_id=master.pk)
        if row is not None:
            if row.description != r["description"]:
                row.description = r["description"]
                row.full_clean(validate_unique=False)
                row.save(update_fields=["description"])
                session.plan.note("images", "updated")
                session.changed.append(row)
            else:
                session.plan.note("images", "unchanged")
            continue
        row = Image(
            uid=uid,
            # A full row: the file's storage name contains the segment's uid.
            segment=Segment.objects.get(pk=master.pk),
            description=r["description"],
            robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
            received=rec.time_in(r["received"], "received"),
        )
        _add_with_file(session, "images", row, r, PHOTO_FORMATS, exclude=["segment"])


def import_recordings(session: ImportSession):
    # A snapshot never changes once stored: a known uid is left as it is.
    for r in session.records("recordings"):
        uid = uuid.UUID(r["uid"])
        master = session.master(r["segment"])
        if session.known("recordings", Recording, [uid], segment_id=master.pk):
            session.plan.note("recordings", "unchanged")
            continue
        row = Recording(
            uid=uid,
            segment=Segment.objects.get(pk=master.pk),
            start=rec.time_in(r["start"], "start"),
            end=rec.time_in(r["end"], "end"),
            topics=r["topics"],
            message_count=r["message_count"],
            size=r["size"],
            reason=r["reason"],
            received=rec.time_in(r["received"], "received"),
        )
        _add_with_file(session, "recordings", row, r, None, field="file", exclude=["segment"])
