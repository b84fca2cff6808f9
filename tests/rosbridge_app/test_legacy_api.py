"""Robots running the original FTT node log into FTT over HTTP, unchanged."""

import base64
import hashlib
import importlib
import io
import re
import uuid
from datetime import UTC, datetime
from pathlib import Path

import pytest
import requests
from PIL import Image as PilImage

from events.models import Segment, Vehicle
from events.services import finality, logs
from events.services.robots import ensure_robot_account
from rosbridge_app.legacy_api.views import UIDS
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.selectors.distances import stored_distances
from tests.support.fkie import FKIE_BAG, full_rate_length, gps_path_length, master_path_length
from tests.support.legacy_node import LegacyNode, jpeg

pytestmark = pytest.mark.django_db(transaction=True)
API_DOC = Path(__file__).resolve().parents[2] / "docs" / "api.md"


@pytest.fixture
def field(live_server):
    """Two robots, each with an open leg and its own robot account."""
    from django.apps import apps

    importlib.import_module("events.migrations.0002_seed_catalogues_and_roles").seed(apps, None)
    event = logs.create_test_event(location="Wachtberg")
    robots = {}
    for key in ("husky", "jackal"):
        vehicle = Vehicle.objects.create(key=key, short_description=key.title())
        leg = logs.create_leg(shift=logs.create_shift(test_event=event, vehicle=vehicle))
        token = ensure_robot_account(f"{key}-robot", [vehicle]).token
        address = f"{live_server.url.removeprefix('http://')}/legacy/{token}"
        robots[key] = {
            "leg": leg,
            "address": address,
            "url": f"http://{address}",
            "vehicle": vehicle,
            "token": token,
        }
    return robots


def call(robot, verb, path, body=None, raw: bytes | None = None):
    if raw is not None:
        return requests.request(verb, f"{robot['url']}/{path}", data=raw, timeout=30)
    return requests.request(verb, f"{robot['url']}/{path}", json=body, timeout=30)


def masters(leg):
    return list(Segment.objects.filter(leg=leg, parent__isnull=True).order_by("start", "id"))


@pytest.mark.skipif(not FKIE_BAG.exists(), reason="fkie_test.bag not available")
def test_the_fkie_recording_through_the_original_node(field):
    from rosbridge_app.collector.bag import bag_messages

    robot = field["husky"]
    node = LegacyNode(robot["address"])
    posted = []  # (mode switch number, lng, lat) of every pose the node had stored
    switches = 0
    for m in bag_messages(FKIE_BAG):
        t = m.time_ns / 1e9
        node.on_camera(t)
        if m.msgtype.endswith("RobotMode"):
            before = node.mode
            node.on_mode(t, m.msg.val)
            if node.mode != before:
                switches += 1
                lng, lat, _ = node.last_fix
                posted.append((switches, lng, lat))
        elif m.msgtype.endswith("NavSatFix"):
            stamp = m.msg.header.stamp.sec + m.msg.header.stamp.nanosec / 1e9
            sent = len(node.answers)
            node.on_fix(t, m.msg.longitude, m.msg.latitude, stamp)
            if len(node.answers) > sent and node.answers[-1][2] == 200:
                posted.append((switches, m.msg.longitude, m.msg.latitude))
    node.stop()

    refused = [a for a in node.answers if a[2] != 200]
    assert not refused, refused[:5]
    assert all(a[3].startswith('"[INFO]') for a in node.answers)
    found = masters(robot["leg"])
    assert [m.segment_type_id for m in found] == ["ito", "auto", "ito", "auto", "ito"]
    assert all(m.end is not None for m in found)
    for m in found:
        reasons = list(m.children.values_list("ito_reason_id", flat=True))
        assert reasons == (["unassigned"] if m.segment_type_id == "ito" else [])
    # Every pose the node sent lies on the master of its mode, and each master's
    # distance is the path through them.
    for number, master in enumerate(found, start=1):
        truth = [(lng, lat) for n, lng, lat in posted if n == number]
        assert master.poses.count() == len(truth)
        assert master_path_length(master) == pytest.approx(gps_path_length(truth), abs=1e-6)
    # The node sends one fix per 2 s, so each take-over's track ends up to 2 s of
    # driving (about 2 m here) before the next switch: within that of the
    # original's own report figures, and of ftt_collect's full-rate track.
    original = [42.72, 44.62, 24.16, 71.98, 39.56]
    for master, figure in zip(found, original, strict=True):
        assert figure - 2.5 < master_path_length(master) <= figure + 0.05
    # What FTT stores is what docs/api.md says, to the centimetre.
    said = re.search(
        r"the five take-overs as ([\d., and]+) m", " ".join(API_DOC.read_text().split())
    )
    documented = [float(x) for x in re.findall(r"\d+\.\d+", said.group(1))]
    stored = stored_distances(found)
    shown = [round(stored[m.pk], 2) for m in found]
    assert shown == documented, shown
    recorded = sum(master_path_length(m) for m in found)
    assert 0.97 < recorded / full_rate_length() <= 1.0
    # The node's camera buffer: three frames at each of the five switches.
    assert [m.images.count() for m in found] == [3, 3, 3, 3, 3]
    assert Pose.objects.filter(segment__leg=field["jackal"]["leg"]).count() == 0


def test_robot_state_and_the_segment_dance(field):
    robot = field["husky"]
    refused = call(robot, "GET", "robot_state")
    assert refused.status_code == 400
    assert refused.json()["message"].startswith("[ERROR] (LogError): No open segment")
    body = {"leg_id": "Current Leg", "segment_type_id": 2, "ito_reason_id": 11}
    assert (
        call(robot, "POST", "segment", body).json() == "[INFO]: Created AUTO parent segment entry."
    )
    assert call(robot, "GET", "robot_state").json() == ["AUTO"]
    # An AUTO report while AUTO is open is not an error for FTT: the node gets 200
    # and goes on posting poses (the original answered 400 and the node stalled).
    again = call(robot, "POST", "segment", body)
    assert again.status_code == 200 and again.json().startswith("[INFO]")
    assert call(robot, "POST", "segment", {**body, "segment_type_id": 1}).status_code == 200
    assert call(robot, "GET", "robot_state").json() == ["ITO"]
    ito = masters(robot["leg"])[-1]
    assert list(ito.children.values_list("ito_reason_id", flat=True)) == ["unassigned"]
    closed = call(robot, "PUT", "segment", {"id": "Current Segment", "action": "close"})
    assert closed.json() == "[INFO]: Closed segment open entries."
    # Closing again: the node takes 400 as "already closed".
    assert (
        call(robot, "PUT", "segment", {"id": "Current Segment", "action": "close"}).status_code
        == 400
    )


def test_poses_local_poses_maps_and_images_are_stored_once(field):
    robot = field["husky"]
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    master = masters(robot["leg"])[-1]
    fix = {"segment_id": "Current Segment", "lng": 7.1285, "lat": 50.6161, "orig_secs": 1.7e9}
    assert call(robot, "POST", "pose", {**fix, "pose_source_id": 1}).status_code == 200
    # The node posts a fix again when the answer was lost: stored once.
    assert call(robot, "POST", "pose", fix).json() == "[INFO]: This pose is stored already."
    assert master.poses.count() == 1

    local = {"segment_id": "Current Segment", "frame_id": "/map", "orig_secs": 1.7e9}
    failed_tf = call(robot, "POST", "local_pose", {**local, "x": 0.0, "y": 0.0})
    assert failed_tf.status_code == 200 and failed_tf.json().startswith("[WARN]")
    assert call(robot, "POST", "local_pose", {**local, "x": 3.5, "y": -2.0}).status_code == 200
    assert list(LocalPose.objects.values_list("x", "y", "frame")) == [(3.5, -2.0, "map")]

    grid = {
        "shift_id": "Current Shift",
        "frame_id": "map",
        "width": 32,
        "height": 24,
        "resolution": 0.05,
        "origin_x": -1.0,
        "origin_y": -2.0,
        "image_data": jpeg(40),
        "orig_secs": 1.7e9,
    }
    assert call(robot, "POST", "map_image", grid).status_code == 200
    # After the first map the node only PUTs; a PUT without the origin keeps it.
    update = {"shift_id": "Current Shift", "image_data": jpeg(200), "orig_secs": 1.7e9 + 5}
    assert call(robot, "PUT", "map_image", update).status_code == 200
    newest = MapImage.objects.order_by("-received", "-id").first()
    assert MapImage.objects.count() == 2
    assert (newest.origin_x, newest.origin_y, newest.width) == (-1.0, -2.0, 32)
    with PilImage.open(newest.image.open("rb")) as picture:
        assert (picture.format, picture.mode, picture.size) == ("PNG", "L", (32, 24))

    frame = {"segment_id": "Current Segment", "image_data": jpeg(99), "orig_secs": 1.7e9 + 1}
    assert call(robot, "POST", "image", {**frame, "image_filename": "rgb_img1"}).status_code == 200
    # A stalled camera: the same buffered frame again at the next switch.
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 1})
    assert call(robot, "POST", "image", {**frame, "image_filename": "rgb_img2"}).status_code == 200
    assert Image.objects.count() == 1
    with PilImage.open(io.BytesIO(Image.objects.get().image.read())) as picture:
        assert picture.format == "JPEG"


def test_the_same_fixes_sent_into_a_new_leg_are_stored_there(field):
    """Issue 47: a retry is known by its uid within its segment; the same stamps
    in a new leg of the same vehicle are new data (5 requests)."""
    robot = field["husky"]
    fix = {"segment_id": "Current Segment", "lng": 7.1285, "lat": 50.6161, "orig_secs": 1.7e9}
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    assert call(robot, "POST", "pose", fix).json() == "[INFO]: Created pose entry."
    new_leg = logs.create_leg(shift=robot["leg"].shift)
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})

    answer = call(robot, "POST", "pose", fix)

    assert answer.json() == "[INFO]: Created pose entry."
    assert [m.poses.count() for m in masters(robot["leg"])] == [1]
    assert [m.poses.count() for m in masters(new_leg)] == [1]


def test_a_frame_whose_uid_another_vehicle_took_is_refused(field, live_server):
    """Issue 42: the original's uids are made from what the node sends, so another
    robot can send one first; the frame is then refused, not answered "stored"."""
    husky, jackal = field["husky"], field["jackal"]
    for robot in (husky, jackal):
        call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    frame = {"segment_id": "Current Segment", "image_data": jpeg(99), "orig_secs": 1.7e9 + 1}
    picture = base64.b64decode(frame["image_data"])
    stamp = datetime.fromtimestamp(frame["orig_secs"], UTC)
    taken = uuid.uuid5(
        UIDS, f"{husky['vehicle'].pk}|image|{stamp}|{hashlib.sha256(picture).hexdigest()}"
    )
    theirs = masters(jackal["leg"])[-1]
    sent = requests.post(
        f"{live_server.url}/api/images/",
        data={"segment": theirs.pk, "uid": str(taken)},
        files={"image": ("frame.jpg", picture, "image/jpeg")},
        headers={"Authorization": f"Token {jackal['token']}"},
        timeout=30,
    )
    assert sent.status_code == 201, sent.content

    answer = call(husky, "POST", "image", frame)

    assert answer.status_code == 400
    assert answer.json()["message"].startswith("[ERROR] (RuleError)")
    assert "uid" in answer.json()["message"]
    assert list(Image.objects.values_list("segment_id", flat=True)) == [theirs.pk]


def test_a_final_test_event_takes_no_pose_from_the_original_node(field):
    """Issue 46: the node names a segment of a test event that is final by now."""
    robot = field["husky"]
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    master = masters(robot["leg"])[-1]
    event = robot["leg"].shift.test_event
    logs.close_test_event(event)
    finality.finalise_test_event(event)
    fix = {"segment_id": master.pk, "lng": 7.1285, "lat": 50.6161, "orig_secs": 1.7e9}

    answer = call(robot, "POST", "pose", fix)

    assert answer.status_code == 403
    assert answer.json()["message"].startswith("[ERROR] (AuthError): This test event is final")
    assert master.poses.count() == 0


def test_a_robot_never_writes_into_another_vehicles_leg(field, live_server):
    husky, jackal = field["husky"], field["jackal"]
    call(husky, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    call(jackal, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    husky_master = masters(husky["leg"])[-1]
    fix = {"lng": 7.1, "lat": 50.6, "orig_secs": 1.7e9}
    foreign = call(jackal, "POST", "pose", {**fix, "segment_id": husky_master.pk})
    assert foreign.status_code == 403
    assert foreign.json()["message"].startswith("[ERROR] (AuthError)")
    leg = call(jackal, "POST", "segment", {"leg_id": husky["leg"].pk, "segment_type_id": 1})
    assert leg.status_code == 403
    assert call(jackal, "POST", "pose", {**fix, "segment_id": "Current Segment"}).status_code == 200
    assert husky_master.poses.count() == 0
    assert Pose.objects.filter(segment__leg=jackal["leg"]).count() == 1
    assert masters(husky["leg"])[-1].segment_type_id == "auto"

    unknown = requests.post(f"{live_server.url}/legacy/not-a-token/pose", json=fix, timeout=10)
    assert unknown.status_code == 401
    assert unknown.json()["message"].startswith("[ERROR] (AuthError)")


HTML = base64.b64encode(b"<html><script>alert(1)</script></html>").decode()


@pytest.mark.parametrize(
    ("verb", "path", "body"),
    [
        ("POST", "segment", b"not json"),
        ("POST", "segment", b"[1, 2]"),
        ("POST", "segment", {}),
        ("POST", "segment", {"leg_id": 1.5, "segment_type_id": 1}),
        ("POST", "segment", {"leg_id": None, "segment_type_id": 1}),
        ("POST", "segment", {"leg_id": "Current Leg", "segment_type_id": "1"}),
        ("POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 3}),
        ("POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2, "lat": 95, "lng": 7}),
        (
            "POST",
            "segment",
            b'{"leg_id": "Current Leg", "segment_type_id": 2, "lat": NaN, "lng": 7}',
        ),
        (
            "POST",
            "segment",
            {"leg_id": "Current Leg", "segment_type_id": 2, "orig_starttime_secs": 1e20},
        ),
        ("PUT", "segment", {"id": "Current Segment"}),
        ("PUT", "segment", {"id": "Current Segment", "action": "explode"}),
        ("PUT", "segment", {"id": "Current Segment", "action": "edit", "ito_reason_id": 3}),
        ("POST", "pose", {"segment_id": "Current Segment", "lat": 50.6, "lng": 7.1}),
        ("POST", "pose", {"segment_id": {"a": 1}, "lat": 50.6, "lng": 7.1, "orig_secs": 1}),
        ("POST", "pose", {"segment_id": "Current Segment", "lat": "x", "lng": 7.1, "orig_secs": 1}),
        (
            "POST",
            "local_pose",
            b'{"segment_id": "Current Segment", "frame_id": "\\ud800", '
            b'"x": 1, "y": 2, "orig_secs": 1}',
        ),
        ("PUT", "map_image", {"shift_id": "Current Shift", "image_data": jpeg(10), "orig_secs": 1}),
        (
            "POST",
            "map_image",
            {
                "shift_id": "Current Shift",
                "frame_id": "map",
                "width": "ten",
                "height": 2,
                "resolution": 1,
                "origin_x": 0,
                "origin_y": 0,
                "image_data": jpeg(10),
            },
        ),
        (
            "POST",
            "map_image",
            {
                "shift_id": "Current Shift",
                "frame_id": "map",
                "width": 2,
                "height": 2,
                "resolution": 1,
                "origin_x": 0,
                "origin_y": 0,
                "image_data": "not base64!!",
            },
        ),
        ("POST", "image", {"segment_id": "Current Segment", "image_data": HTML, "orig_secs": 1}),
        ("GET", "nothing_here", None),
    ],
)
def test_malformed_requests_get_a_4xx_in_the_originals_shape(field, verb, path, body):
    robot = field["husky"]
    call(robot, "POST", "segment", {"leg_id": "Current Leg", "segment_type_id": 2})
    if isinstance(body, bytes):
        answer = call(robot, verb, path, raw=body)
    else:
        answer = call(robot, verb, path, body)
    assert 400 <= answer.status_code < 500, (answer.status_code, answer.text[:300])
    if path != "nothing_here":
        assert answer.json()["message"].startswith("[ERROR] ("), answer.text
    assert Pose.objects.count() == LocalPose.objects.count() == Image.objects.count() == 0
