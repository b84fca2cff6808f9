"""Every writer adds a change-feed row with each change a browser should see."""

from datetime import timedelta

import pytest
from django.db import transaction
from django.utils import timezone

from common.errors import RuleViolation
from events import feed
from events.models import Announcement
from events.services import logs, notes, segments
from telemetry.services import pose_writes
from tests.support.modes import start_auto

# On SpatiaLite too: feed rows wake readers by trigger on PostgreSQL, by the writer on SpatiaLite.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]


def kinds_since(last_id):
    return [(e.kind, e.payload.get("leg")) for e in Announcement.objects.filter(id__gt=last_id)]


def last_id():
    return Announcement.objects.order_by("-id").values_list("id", flat=True).first() or 0


def test_new_segment_and_poses_are_announced_with_their_leg(leg):
    before = last_id()
    master = start_auto(leg)
    pose_writes.store_poses(master, [pose_writes.GpsFix(7.1, 50.6), pose_writes.GpsFix(7.2, 50.7)])
    events = list(Announcement.objects.filter(id__gt=before))
    assert [e.kind for e in events] == ["segment", "poses"]
    assert {e.leg_id for e in events} == {leg.pk}
    assert events[1].payload["points"] == [[7.1, 50.6], [7.2, 50.7]]
    assert events[1].payload["mode"] == "auto"


def test_repeated_pose_batch_announces_nothing_new(leg):
    master = start_auto(leg)
    fix = pose_writes.GpsFix(7.1, 50.6)
    pose_writes.store_poses(master, [fix])
    before = last_id()
    pose_writes.store_poses(master, [fix])
    assert kinds_since(before) == []


def test_rule_violation_rolls_back_its_announcement(test_event):
    logs.close_test_event(test_event)
    before = last_id()
    with pytest.raises(RuleViolation):
        logs.close_test_event(test_event)
    assert kinds_since(before) == []


def test_log_levels_and_notes_are_announced(shift, person):
    before = last_id()
    leg = logs.create_leg(shift=shift)
    child = segments.new_manual_segment(leg)
    note = notes.add_note(child, text="Grüße", author=person)
    notes.delete_note(note)
    assert [k for k, _ in kinds_since(before)] == ["log", "segment", "note", "deleted"]


def test_prune_drops_only_old_events(leg):
    old = feed.announce("log", leg)
    Announcement.objects.filter(pk=old.pk).update(created=timezone.now() - timedelta(hours=2))
    fresh = feed.announce("log", leg)
    assert feed.prune() == 1
    remaining = set(Announcement.objects.values_list("pk", flat=True))
    assert fresh.pk in remaining and old.pk not in remaining


def test_announce_inside_failed_transaction_leaves_nothing(leg):
    before = last_id()
    with pytest.raises(RuntimeError), transaction.atomic():
        feed.announce("segment", leg, segment=1)
        raise RuntimeError
    assert kinds_since(before) == []


def test_the_feed_carries_the_usable_points_as_stored_in_driving_order(leg):
    """What a browser draws live is what a reload draws: no-fix fixes are left
    out, a batch is announced in driving order, and a late batch that falls
    between stored points says the track changed instead of being appended."""
    master = start_auto(leg)
    t0 = timezone.now()

    def fix(lon, seconds, **kwargs):
        return pose_writes.GpsFix(lon, 50.0, robot_stamp=t0 + timedelta(seconds=seconds), **kwargs)

    before = last_id()
    # Sent out of order, with a fix that has no position.
    pose_writes.store_poses(master, [fix(7.3, 30), fix(7.1, 10), fix(7.2, 20, fix_status=-1)])
    (batch,) = Announcement.objects.filter(id__gt=before)
    assert batch.payload["points"] == [[7.1, 50.0], [7.3, 50.0]]
    before = last_id()
    pose_writes.store_pose(master.pk, fix(7.4, 40, fix_status=-1))
    assert kinds_since(before) == []  # nothing to draw
    pose_writes.store_poses(master, [fix(7.15, 15), fix(7.25, 25)])
    (late,) = Announcement.objects.filter(id__gt=before)
    assert late.payload["changed"] is True and "points" not in late.payload
    before = last_id()
    pose_writes.store_pose(master.pk, fix(7.5, 50))
    (appended,) = Announcement.objects.filter(id__gt=before)
    assert appended.payload["points"] == [[7.5, 50.0]]
