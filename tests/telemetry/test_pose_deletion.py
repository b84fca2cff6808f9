"""Deleting a pose keeps the segment's stored figures exact (issue 46, item 2): on
every deletion path, ``ftt_recount_figures`` finds no difference afterwards and
the segment's distance is that of the poses left.  Run on PostGIS and on
SpatiaLite (the figures' SQL differs)."""

import io
from datetime import UTC, datetime, timedelta

import pytest
from django.core.management import call_command

from events.models import SegmentType
from events.services import deletion, segments
from telemetry.models import LocalPose, Pose
from telemetry.services import pose_writes
from telemetry.services.segment_figures import recount_figures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

pytestmark = pytest.mark.django_db

T0 = datetime(2026, 5, 4, 10, 0, tzinfo=UTC)


@pytest.fixture
def master(leg):
    """An AUTO master with five fixes and five local poses, a detour at the third."""
    master = segments.report_mode(leg, SegmentType.AUTO).master
    points = [(0, 0), (1, 0), (1, 5), (2, 0), (3, 0)]
    pose_writes.store_poses(
        master,
        [
            pose_writes.GpsFix(
                7.0 + x * 1e-4, 50.6 + y * 1e-4, robot_stamp=T0 + timedelta(seconds=i)
            )
            for i, (x, y) in enumerate(points)
        ],
    )
    pose_writes.store_local_poses(
        master,
        [
            pose_writes.MapPose(float(x), float(y), "map", robot_stamp=T0 + timedelta(seconds=i))
            for i, (x, y) in enumerate(points)
        ],
    )
    return master


def _detour(model, master):
    return model.objects.filter(segment=master).order_by("robot_stamp")[2]


def _recount_finds_nothing(master) -> None:
    assert recount_figures([master.pk]) == {}
    out = io.StringIO()
    call_command("ftt_recount_figures", stdout=out)
    assert "0 figures differed" in out.getvalue(), out.getvalue()


def _length(master, mode) -> float:
    return master.figures.get(mode=mode).length


@pytest.mark.parametrize(
    "model, mode, url", [(Pose, GPS_TRACK, "poses"), (LocalPose, LOCAL_TRACK, "local-poses")]
)
def test_a_pose_deleted_through_the_api_leaves_exact_figures(master, api_client, model, mode, url):
    before = _length(master, mode)

    answer = api_client("administrator").delete(f"/api/{url}/{_detour(model, master).pk}/")

    assert answer.status_code == 204, answer.content
    assert _length(master, mode) < before
    _recount_finds_nothing(master)


def test_poses_deleted_in_the_admin_leave_exact_figures(master, client, django_user_model):
    client.force_login(django_user_model.objects.create_superuser("root", password="pw"))
    detour = _detour(Pose, master)
    before = _length(master, GPS_TRACK)

    answer = client.post(f"/admin/telemetry/pose/{detour.pk}/delete/", {"post": "yes"})
    assert answer.status_code == 302
    first = Pose.objects.filter(segment=master).order_by("robot_stamp").first()
    chosen = {"action": "delete_selected", "_selected_action": [first.pk], "post": "yes"}
    assert client.post("/admin/telemetry/pose/", chosen).status_code == 302

    assert Pose.objects.filter(segment=master).count() == 3
    assert _length(master, GPS_TRACK) < before
    _recount_finds_nothing(master)


def test_a_pose_deleted_by_the_deletion_service_leaves_exact_figures(master):
    deletion.delete(_detour(Pose, master))
    deletion.delete(_detour(LocalPose, master))

    _recount_finds_nothing(master)
