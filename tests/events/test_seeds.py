"""Catalogues and roles exist right after migrate, as the original tool's users know them."""

from django.contrib.auth.models import Group

from events.models import ItoReason, SegmentType, Weather


def test_catalogues_are_seeded_with_the_original_keys_and_colours(db):
    assert Weather.objects.count() == 6
    assert set(SegmentType.objects.values_list("key", "color")) == {
        ("ito", "255,0,0"),
        ("auto", "0,255,0"),
        ("unknown", "150,150,150"),
    }
    assert ItoReason.objects.count() == 12
    assert ItoReason.objects.get(key="safety").color == "255,0,0"
    assert ItoReason.objects.get(key="other").color == "180,180,180"


def test_only_non_stop_goal_and_end_of_shift_do_not_count_as_interventions(db):
    not_counted = set(
        ItoReason.objects.filter(counts_as_intervention=False).values_list("key", flat=True)
    )
    assert not_counted == {"non_stop", "goal", "end_shift"}


def test_role_groups_exist_with_growing_rights(db):
    perms = {
        g.name: set(g.permissions.values_list("codename", flat=True))
        for g in Group.objects.filter(name__in=["viewer", "operator", "administrator"])
    }
    assert "view_segment" in perms["viewer"] and "change_segment" not in perms["viewer"]
    assert "change_segment" in perms["operator"] and "change_vehicle" not in perms["operator"]
    assert "change_vehicle" in perms["administrator"]
    assert "change_itoreason" in perms["administrator"]
    assert perms["viewer"] < perms["operator"] < perms["administrator"]


def test_the_robot_group_may_only_add_what_a_robot_records(db):
    robot = set(Group.objects.get(name="robot").permissions.values_list("codename", flat=True))
    assert robot == {
        "add_segment",
        "add_pose",
        "add_localpose",
        "add_mapimage",
        "add_image",
        "add_recording",
    }
