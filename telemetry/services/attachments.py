"""Storing files the robot or an operator attaches to a segment: camera frames
and photos (images) and the collector's black-box snapshots (recordings)."""

import os
import uuid
from datetime import datetime
from pathlib import Path

from django.core.files import File
from django.core.files.base import ContentFile
from django.db import transaction
from django.utils.translation import gettext as _

from common.errors import RuleViolation
from common.retries import stored_row
from events.feed import announce_and_return, announce_row
from events.models import Segment
from events.services.finality import require_amendable, require_amendable_row
from telemetry.models import Image, Recording
from telemetry.pictures import checked_picture


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
    if existing := stored_row(Image, uid, segment_id=segment.master_id):
        return existing
    if not content:
        raise RuleViolation({"image": [_("The image is empty.")]})
    require_amendable(shifts__legs=segment.leg_id)
    suffix = checked_picture(content)
    image = Image(segment=segment.master, description=description, robot_stamp=robot_stamp)
    if uid is not None:
        image.uid = uid
    image.image.save(f"image.{suffix}", ContentFile(content), save=False)
    image.save()
    return announce_and_return(image)


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
    if existing := stored_row(Recording, uid, segment_id=segment.master_id):
        return existing
    if end < start:
        raise RuleViolation({"end": [_("The window ends before it starts.")]})
    require_amendable(shifts__legs=segment.leg_id)
    path = Path(path)
    recording = Recording(
        segment=segment.master,
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
    return announce_and_return(recording)


class _HardLink(File):
    """A hard link to a file, which the storage moves in: a rename when the media
    directory is on the same filesystem, a copy otherwise (Django's
    ``file_move_safe``)."""

    def temporary_file_path(self) -> str:
        return self.name


def _store_file(recording: Recording, path: Path) -> None:
    """Put the file into media storage without copying it where possible: the
    collector stores a snapshot of many megabytes in the same transaction as the
    mode and pose rows behind it, which a copy would hold open."""
    link = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.link")
    try:
        os.link(path, link)
    except OSError:  # no hard links there (another kind of filesystem)
        with path.open("rb") as f:
            recording.file.save(path.name, File(f), save=False)
        return
    try:
        recording.file.save(path.name, _HardLink(None, str(link)), save=False)
    finally:
        link.unlink(missing_ok=True)  # left only if the storage failed


@transaction.atomic
def delete_image(image: Image) -> None:
    require_amendable_row(image)
    announce_row(image, deleted=True)
    image.delete()


@transaction.atomic
def delete_recording(recording: Recording) -> None:
    require_amendable_row(recording)
    announce_row(recording, deleted=True)
    recording.delete()
