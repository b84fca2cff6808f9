"""Deleting log levels takes everything below along; configuration in use stays."""

import pytest
from django.core.files.storage import default_storage

from common.errors import RuleViolation
from events.models import Leg, Note, Segment, Shift
from events.services import deletion, notes, segments
from telemetry.models import Image, MapImage, Pose
from telemetry.services import attachments, map_images, pose_writes
from tests.support.images import PNG


@pytest.fixture
def recorded_leg(leg, person, media_root, django_capture_on_commit_callbacks):
    master = segments.report_mode(leg, "ito").master
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.1, 50.6)])
    image = attachments.attach_image(master, content=PNG)
    map_image, _ = map_images.store_map(
        leg.shift,
        png=PNG,
        frame="map",
        width=1,
        height=1,
        resolution=0.05,
        origin_x=0.0,
        origin_y=0.0,
    )
    notes.add_note(master.children.get(), text="Hindernis", author=person)
    return leg, [image.image.name, map_image.image.name]


def test_deleting_a_test_event_removes_everything_below_and_the_files(
    recorded_leg, django_capture_on_commit_callbacks
):
    leg, files = recorded_leg
    assert all(default_storage.exists(name) for name in files)
    with django_capture_on_commit_callbacks(execute=True):
        deletion.delete(leg.shift.test_event)
    for model in (Shift, Leg, Segment, Pose, Image, MapImage, Note):
        assert not model.objects.exists(), model.__name__
    assert not any(default_storage.exists(name) for name in files)


def test_deleting_a_leg_keeps_its_shift_and_the_shift_map(recorded_leg):
    leg, _ = recorded_leg
    deletion.delete(leg)
    assert Shift.objects.filter(pk=leg.shift_id).exists()
    assert MapImage.objects.filter(shift=leg.shift_id).exists()
    assert not Segment.objects.exists()


def test_configuration_in_use_cannot_be_deleted_and_the_error_says_where(shift):
    with pytest.raises(RuleViolation) as exc:
        deletion.delete(shift.vehicle)
    message = " ".join(exc.value.messages)
    assert "shifts" in message and "Shift 1" in message


def test_person_who_wrote_a_note_cannot_be_deleted(recorded_leg, person):
    with pytest.raises(RuleViolation, match="note"):
        deletion.delete(person)


def test_unused_configuration_can_be_deleted(other_vehicle):
    deletion.delete(other_vehicle)
    assert not type(other_vehicle).objects.filter(pk=other_vehicle.pk).exists()
