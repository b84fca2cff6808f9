"""Robot data lands on master segments, once, with nothing invented."""

import math
import os
import uuid
from datetime import UTC, datetime

import pytest
from django.utils import timezone

from common.errors import RuleViolation
from events.models import PoseSource
from events.services import segments
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.services import attachments, map_images, pose_writes
from tests.support.images import PNG


@pytest.fixture
def ito(leg):
    return segments.report_mode(leg, "ito").master


def test_fixes_sent_for_a_reason_are_stored_on_its_master(ito):
    child = ito.children.get()
    pose_writes.store_poses(child, [pose_writes.GpsFix(7.0, 50.0)])
    assert Pose.objects.get().segment == ito


def test_pose_keeps_altitude_fix_quality_accuracy_and_default_pose_source(ito, pose_source):
    fix = pose_writes.GpsFix(7.0, 50.0, altitude=123.4, fix_status=2, horizontal_accuracy=0.02)
    pose_writes.store_poses(ito, [fix])
    pose = Pose.objects.get()
    assert (pose.altitude, pose.fix_status, pose.horizontal_accuracy) == (123.4, 2, 0.02)
    assert pose.pose_source == pose_source


def test_a_single_pose_takes_the_legs_default_pose_source_as_it_is_now(ito, pose_source):
    pose_writes.store_pose(ito.pk, pose_writes.GpsFix(7.0, 50.0))
    rtk = PoseSource.objects.create(key="rtk", short_description="RTK base 2")
    ito.leg.default_pose_source = rtk
    ito.leg.save(update_fields=["default_pose_source"])
    pose_writes.store_pose(ito.pk, pose_writes.GpsFix(7.0, 50.1))
    assert [p.pose_source for p in Pose.objects.order_by("id")] == [pose_source, rtk]


def test_a_batch_keeps_every_value_exactly_including_the_missing_ones(ito):
    plus_two = timezone.get_fixed_timezone(120)
    fixes = [
        pose_writes.GpsFix(
            -0.1234567890123, -45.987654321, altitude=-12.5, horizontal_accuracy=1e-9
        ),
        pose_writes.GpsFix(179.9999999, 89.9999999, altitude=None, horizontal_accuracy=None),
        pose_writes.GpsFix(
            7.0, 50.0, fix_status=-1, robot_stamp=datetime(2026, 5, 4, 12, 0, 1, 250001, plus_two)
        ),
        pose_writes.GpsFix(7.0, 50.0, robot_stamp=datetime(1999, 12, 31, 23, 59, 59, 999999, UTC)),
    ]
    pose_writes.store_poses(ito, fixes)
    stored = {p.uid: p for p in Pose.objects.all()}
    for fix in fixes:
        pose = stored[fix.uid]
        assert (pose.point.x, pose.point.y) == (fix.longitude, fix.latitude)
        assert (pose.altitude, pose.horizontal_accuracy) == (fix.altitude, fix.horizontal_accuracy)
        assert (pose.fix_status, pose.robot_stamp) == (fix.fix_status, fix.robot_stamp)


def test_whole_degrees_beside_fractional_ones_are_stored_as_given(ito):
    fixes = [
        pose_writes.GpsFix(7, 50, altitude=3, horizontal_accuracy=1),
        pose_writes.GpsFix(7.5, 50.25, altitude=3.5, horizontal_accuracy=0.5),
    ]
    pose_writes.store_poses(ito, fixes)
    stored = {p.uid: p for p in Pose.objects.all()}
    for fix in fixes:
        pose = stored[fix.uid]
        assert (pose.point.x, pose.point.y) == (fix.longitude, fix.latitude)
        assert (pose.altitude, pose.horizontal_accuracy) == (fix.altitude, fix.horizontal_accuracy)


def test_retried_points_are_stored_once(ito):
    fixes = [pose_writes.GpsFix(7.0 + i * 1e-5, 50.0, uid=uuid.uuid4()) for i in range(5)]
    assert pose_writes.store_poses(ito, fixes) == 5
    assert pose_writes.store_poses(ito, fixes) == 0
    assert Pose.objects.count() == 5


def test_non_finite_values_are_refused_and_nothing_is_written(ito):
    fixes = [pose_writes.GpsFix(7.0, 50.0), pose_writes.GpsFix(7.0, 50.0, altitude=math.inf)]
    with pytest.raises(RuleViolation):
        pose_writes.store_poses(ito, fixes)
    assert not Pose.objects.exists()


def test_local_pose_keeps_yaw_and_zero_coordinates(ito):
    pose_writes.store_local_poses(ito, [pose_writes.MapPose(0.0, 0.0, "map", yaw=1.5)])
    pose = LocalPose.objects.get()
    assert (pose.x, pose.y, pose.yaw, pose.frame) == (0.0, 0.0, 1.5, "map")


def test_unchanged_map_is_not_stored_again_but_a_changed_one_is(leg, media_root):
    meta = dict(frame="map", width=1, height=1, resolution=0.05, origin_x=1.0, origin_y=2.0)
    first, stored = map_images.store_map(leg.shift, png=PNG, origin_yaw=0.3, **meta)
    again, stored_again = map_images.store_map(leg.shift, png=PNG, origin_yaw=0.3, **meta)
    moved, stored_moved = map_images.store_map(leg.shift, png=PNG, origin_yaw=0.5, **meta)
    assert (stored, stored_again, stored_moved) == (True, False, True)
    assert again == first
    assert MapImage.objects.count() == 2
    assert leg.shift.maps.latest() == moved


def test_a_batch_of_maps_is_stored_in_order_like_one_map_at_a_time(leg, media_root):
    meta = dict(frame="map", width=1, height=1, resolution=0.05, origin_x=1.0, origin_y=2.0)
    retried = uuid.uuid4()
    map_images.store_map(leg.shift, png=PNG, origin_yaw=0.1, uid=retried, **meta)
    batch = [
        map_images.MapPicture(png=PNG, origin_yaw=0.1, uid=retried, **meta),  # a retry
        map_images.MapPicture(png=PNG, origin_yaw=0.2, **meta),
        map_images.MapPicture(png=PNG, origin_yaw=0.2, **meta),  # unchanged
        map_images.MapPicture(png=PNG, origin_yaw=0.3, uid=uuid.uuid4(), **meta),
    ]
    results = map_images.store_maps(leg.shift, batch)
    assert [stored for _, stored in results] == [False, True, False, True]
    assert results[2][0] == results[1][0]
    yaws = list(leg.shift.maps.order_by("received", "id").values_list("origin_yaw", flat=True))
    assert yaws == [0.1, 0.2, 0.3]
    assert leg.shift.maps.latest() == results[3][0]
    assert all(m.image.read() == PNG for m in leg.shift.maps.all())


def test_images_are_files_in_media_storage_on_the_master(ito, media_root):
    image = attachments.attach_image(ito.children.get(), content=PNG)
    assert image.segment == ito
    assert (media_root / image.image.name).read_bytes() == PNG
    assert Image.objects.count() == 1


def test_empty_image_is_refused(ito, media_root):
    with pytest.raises(RuleViolation):
        attachments.attach_image(ito, content=b"")


def test_a_snapshot_is_stored_without_a_second_copy_and_its_pending_file_stays(
    ito, media_root, tmp_path
):
    pending = tmp_path / "snapshot-1.mcap"
    pending.write_bytes(b"MCAP" * 1000)
    stored = attachments.attach_recording(
        ito, path=pending, start=timezone.now(), end=timezone.now(), topics={}
    )
    assert stored.file.read() == b"MCAP" * 1000
    # The collector removes the pending file only after the commit.
    assert pending.read_bytes() == b"MCAP" * 1000
    # Same filesystem: the stored file is the pending file's data, not a copy of it.
    assert os.path.samefile(stored.file.path, pending)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["media", "snapshot-1.mcap"]


def test_a_snapshot_is_copied_where_it_cannot_be_linked(ito, media_root, tmp_path, monkeypatch):
    pending = tmp_path / "snapshot-1.mcap"
    pending.write_bytes(b"MCAP" * 1000)

    def no_links(source, target):
        raise OSError(18, "Invalid cross-device link")

    monkeypatch.setattr(attachments.os, "link", no_links)
    stored = attachments.attach_recording(
        ito, path=pending, start=timezone.now(), end=timezone.now(), topics={}
    )
    assert stored.file.read() == b"MCAP" * 1000
    assert not os.path.samefile(stored.file.path, pending)
    assert pending.read_bytes() == b"MCAP" * 1000
