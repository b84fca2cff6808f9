"""Catalogues and roles exist right after migrate, as the original tool's users know them."""

import json

from django.contrib.auth.models import Group

from events.models import ItoReason, SegmentType, Weather
from tests.support.sites import fresh_site


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


# Run in a freshly migrated installation (tests.support.sites): no seeding after
# migrate, as on a real install.  Prints the status of each admin page an
# administrator opens, and whether finalising a closed test event took effect.
_ADMINISTRATOR_IN_ADMIN = """
import json
from django.contrib.auth.models import Group, User
from django.test import Client
from django.test.utils import setup_test_environment
from events.models import TestEvent
from events.services import logs

setup_test_environment()
ada = User.objects.create_user("ada", password="pw", is_staff=True)
ada.groups.add(Group.objects.get(name="administrator"))
browser = Client()
browser.force_login(ada)
pages = [
    "/admin/events/testcase/",
    "/admin/events/testcase/add/",
    "/admin/events/judgement/",
    "/admin/basemaps/",
    "/admin/basemaps/basemaplayer/add/",
    "/admin/basemaps/eventbasemap/",
    "/admin/events/testevent/",
]
seen = {page: browser.get(page).status_code for page in pages}
event = logs.close_test_event(logs.create_test_event(location="Wachtberg", version="1"))
browser.post(
    "/admin/events/testevent/",
    {"action": "finalise_selected", "_selected_action": [event.pk]},
)
seen["finalised"] = TestEvent.objects.get(pk=event.pk).finalised is not None
print("SEEN" + json.dumps(seen))
"""


def test_on_a_fresh_install_administrators_use_test_plans_basemaps_and_finalising(tmp_path):
    site = fresh_site(tmp_path / "fresh")
    out = site.python(_ADMINISTRATOR_IN_ADMIN)
    seen = json.loads(out.split("SEEN", 1)[1])
    assert seen.pop("finalised") is True
    assert seen == dict.fromkeys(seen, 200)
