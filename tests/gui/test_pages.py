"""The GUI page, login, protected media and the GUI's own JSON reads."""

import json
import re
from datetime import timedelta
from urllib.parse import quote

import pytest
from django.contrib.auth.models import Group, User
from django.utils import timezone

from events.models import Announcement, ItoReason, Performer, PoseSource
from events.services import segments
from rosbridge_app.models import Collector
from rosbridge_app.services import collectors
from telemetry.services import attachments, map_images, pose_writes
from tests.support.images import PNG, jpeg
from tests.support.modes import start_auto
from tests.support.pages import asset_urls, external_assets

pytestmark = pytest.mark.django_db


def member(client, name, role=None, **extra):
    user = User.objects.create_user(name, password="pw", **extra)
    if role:
        user.groups.add(Group.objects.get(name=role))
    client.force_login(user)
    return user


def test_page_needs_a_login(client):
    response = client.get("/")
    assert response.status_code == 302 and response["Location"].startswith("/login/")
    assert "Sign in" in client.get("/login/").content.decode()


def test_administrator_gets_first_run_hint_until_configured(client, vehicle):
    member(client, "ada", "administrator")
    page = client.get("/").content.decode()
    assert "Before the first shift" in page
    assert "Add a performer" in page and "Add a pose source" in page
    assert "Add a vehicle" not in page
    # Accounts and people are named too: the add page takes login, role and name at once.
    assert "Add an account for a person" in page and "/admin/auth/user/add/" in page
    Performer.objects.create(institution="FKIE")
    PoseSource.objects.create(key="gps", short_description="GPS")
    assert "Before the first shift" not in client.get("/").content.decode()


def test_every_script_and_stylesheet_of_the_page_is_served_by_ftt_itself(client):
    # Operators are often offline: Leaflet and our own code must come from this server.
    member(client, "olga", "operator")
    page = client.get("/").content.decode()
    assert external_assets(page) == []
    urls = asset_urls(page)
    assert any(url.endswith("leaflet.js") for url in urls)
    for url in urls:
        response = client.get(url)
        assert response.status_code == 200, url
        assert b"".join(response.streaming_content if response.streaming else [response.content])


def test_the_page_asks_for_every_module_of_the_cockpit_at_once(client):
    member(client, "olga", "operator")
    page = client.get("/").content.decode()
    preloaded = set(re.findall(r'<link rel="modulepreload" href="/static/gui/([\w-]+\.js)"', page))
    # Imported by main.js, by modules main.js imports, and one level further.
    assert {"segments.js", "mapview.js", "maps.js", "api.js"} <= preloaded
    # The comparison page's module is not part of the cockpit.
    assert "compare.js" not in preloaded and "main.js" not in preloaded


def test_operator_gets_no_admin_link_and_account_without_role_is_told(client):
    member(client, "otto", "operator")
    page = client.get("/").content.decode()
    assert 'href="/admin/"' not in page and "pick-event" in page
    client.logout()
    member(client, "nobody")
    assert "has no role" in client.get("/").content.decode()


def quick_buttons(page: str) -> list[str]:
    return re.findall(r'data-quick="([^"]+)">([^<]+)<', page)


def test_quick_reason_buttons_are_the_catalogues_quick_reasons(client):
    member(client, "otto", "operator")
    assert quick_buttons(client.get("/").content.decode()) == [
        ("manual_transit", "Manual transit"),
        ("planner", "Planner"),
        ("safety", "Safety"),
        ("unexpected", "Unexpected"),
    ]
    # An administrator changes which reasons get a button: no template or script to edit.
    ItoReason.objects.filter(key="planner").update(quick=False)
    ItoReason.objects.filter(key="goal").update(quick=True)
    page = client.get("/").content.decode()
    assert ("goal", "Goal reached") in quick_buttons(page)
    assert "planner" not in dict(quick_buttons(page))


def test_photos_are_only_served_to_users_with_a_role(client, leg, media_root):
    master = segments.report_mode(leg, "ito").master
    image = attachments.attach_image(master, content=jpeg(1))
    url = image.image.url
    member(client, "nobody")
    assert client.get(url).status_code == 403
    client.logout()
    member(client, "vera", "viewer")
    response = client.get(url)
    assert response.status_code == 200
    assert b"".join(response.streaming_content) == jpeg(1)


def test_behind_nginx_the_file_transfer_is_handed_to_the_proxy(client, leg, media_root, settings):
    settings.FTT_MEDIA_ACCEL_PREFIX = "/protected-media/"
    master = segments.report_mode(leg, "ito").master
    image = attachments.attach_image(master, content=jpeg(1))
    url = image.image.url
    member(client, "nobody")
    refused = client.get(url)
    assert refused.status_code == 403 and "X-Accel-Redirect" not in refused
    client.logout()
    member(client, "vera", "viewer")
    response = client.get(url)
    assert response.status_code == 200 and response.content == b""
    assert response["Content-Type"] == "image/jpeg"
    stored = image.image.name
    assert response["X-Accel-Redirect"] == "/protected-media/" + quote(stored)
    # Only existing files under the media root are ever named to the proxy.
    for bad in ("../ftt.sqlite3", "images/missing.jpg", "%2e%2e/secret_key"):
        answer = client.get(f"/media/{bad}")
        assert answer.status_code == 404 and "X-Accel-Redirect" not in answer, bad


def test_leg_tracks_carry_points_and_distance(client, leg):
    member(client, "vera", "viewer")
    master = start_auto(leg)
    pose_writes.store_poses(
        master, [pose_writes.GpsFix(7.0, 50.0), pose_writes.GpsFix(7.0, 50.001)]
    )
    data = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()
    track = data["segments"][str(master.pk)]
    assert track["gps"] == [[50.0, 7.0], [50.001, 7.0]]
    assert track["distance_m"] == pytest.approx(111.2, abs=0.5)


def test_local_map_endpoint_places_the_newest_map(client, shift, media_root):
    member(client, "vera", "viewer")
    assert client.get(f"/gui/api/shifts/{shift.pk}/local-map/").json()["map"] is None
    map_images.store_map(
        shift,
        png=PNG,
        frame="map",
        width=10,
        height=20,
        resolution=0.5,
        origin_x=1.0,
        origin_y=2.0,
    )
    data = client.get(f"/gui/api/shifts/{shift.pk}/local-map/").json()
    assert data["map"]["corners"]["top_right"] == [6.0, 12.0]
    assert data["overlay"]["available"] is False


def collector_for(vehicle, **fields):
    defaults = {
        "vehicle": vehicle,
        "parameters": {"params.use_tf": True, "params.pose_min_distance": 0.5},
    }
    return collectors.heartbeat("sim", **(defaults | fields))


def test_logging_can_start_only_with_online_collector_and_open_levels(client, leg, vehicle):
    member(client, "otto", "operator")
    url = f"/gui/api/collectors/?vehicle={vehicle.pk}&leg={leg.pk}"
    assert client.get(url).json() == {
        "collector": None,
        "parameters": [],
        "can_toggle": False,
        "reason": "No collector has reported for this vehicle.",
        "can_snapshot": False,
        "snapshot_reason": "No collector has reported for this vehicle.",
        "stores_nothing": "",
    }
    collector = collector_for(vehicle)
    assert client.get(url).json()["can_toggle"] is True
    start = {"kind": "start_logging", "leg": leg.pk}
    response = client.post(
        f"/gui/api/collectors/{collector.pk}/commands/", start, content_type="application/json"
    )
    assert response.status_code == 202
    assert collector.commands.get().arguments == {"leg": leg.pk}
    from events.services import logs

    logs.close_leg(leg)
    status = client.get(url).json()
    assert status["can_toggle"] is False and "open test event" in status["reason"]


def test_snapshot_now_is_offered_while_logging_and_refused_otherwise(client, leg, vehicle):
    member(client, "otto", "operator")
    snapshots = {"snapshot.enabled": True, "snapshot.before": 20.0, "snapshot.after": 10.0}
    collector = collector_for(vehicle, parameters=snapshots)
    url = f"/gui/api/collectors/?vehicle={vehicle.pk}&leg={leg.pk}"
    status = client.get(url).json()
    assert status["can_snapshot"] is False and "start logging" in status["snapshot_reason"]
    commands = f"/gui/api/collectors/{collector.pk}/commands/"
    body = {"kind": "snapshot", "leg": leg.pk}
    refused = client.post(commands, body, content_type="application/json")
    assert refused.status_code == 409 and "start logging" in str(refused.json())
    collector_for(vehicle, parameters=snapshots, logging=True)
    status = client.get(url).json()
    assert status["can_snapshot"] is True
    assert status["snapshot_reason"] == (
        "Saves the robot's messages from 20 s before to 10 s after now."
    )
    assert client.post(commands, body, content_type="application/json").status_code == 202
    assert collector.commands.get().kind == "snapshot"
    names = [row["name"] for row in status["parameters"]]
    assert {"snapshot.enabled", "snapshot.before", "snapshot.after"} <= set(names)


def test_viewer_cannot_command_and_parameter_types_are_checked(client, leg, vehicle):
    collector = collector_for(vehicle)
    url = f"/gui/api/collectors/{collector.pk}/commands/"
    member(client, "vera", "viewer")
    body = {"kind": "set_parameters", "arguments": {"parameters": {"params.use_tf": "yes"}}}
    assert client.post(url, body, content_type="application/json").status_code == 403
    client.logout()
    member(client, "otto", "operator")
    response = client.post(url, body, content_type="application/json")
    assert response.status_code == 400
    assert response.json()["errors"] == {"params.use_tf": ["params.use_tf must be true or false"]}
    body["arguments"]["parameters"] = {"params.use_tf": False, "params.pose_min_distance": 2}
    assert client.post(url, body, content_type="application/json").status_code == 202
    assert collector.commands.get().arguments["parameters"] == {
        "params.use_tf": False,
        "params.pose_min_distance": 2.0,
    }


def test_photos_open_for_token_clients_with_a_role(client, leg, media_root, role_user):
    master = segments.report_mode(leg, "ito").master
    url = attachments.attach_image(master, content=jpeg(1)).image.url
    viewer, nobody = role_user("viewer"), role_user(None)
    assert client.get(url, HTTP_AUTHORIZATION=f"Token {nobody.auth_token.key}").status_code == 403
    assert client.get(url, HTTP_AUTHORIZATION="Token not-a-token").status_code == 403
    response = client.get(url, HTTP_AUTHORIZATION=f"Token {viewer.auth_token.key}")
    assert response.status_code == 200


def test_leg_tracks_name_segments_as_the_report_does(client, leg):
    member(client, "vera", "viewer")
    auto = start_auto(leg)
    ito = segments.report_mode(leg, "ito").master
    child = ito.children.get()
    labels = client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["labels"]
    assert client.get(f"/gui/api/legs/{leg.pk}/segments/").json()["labels"] == labels
    number = leg.number
    assert labels == {
        str(auto.pk): f"Leg {number} · #1",
        str(ito.pk): f"Leg {number} · #2",
        str(child.pk): f"Leg {number} · #2.1",
    }


def test_favicon_is_served(client):
    answer = client.get("/favicon.ico", follow=True)
    assert answer.status_code == 200
    assert b"<svg" in b"".join(answer.streaming_content if answer.streaming else [answer.content])


def test_a_robot_token_opens_neither_photos_nor_the_guis_data(
    client, leg, vehicle, media_root, robot_client
):
    """Even of its own vehicle: a robot writes, people look."""
    master = segments.report_mode(leg, "ito").master
    url = attachments.attach_image(master, content=jpeg(1)).image.url
    robot = robot_client(vehicle)
    token = f"Token {robot.user.auth_token.key}"
    assert client.get(url, HTTP_AUTHORIZATION=token).status_code == 403
    assert robot.get(f"/gui/api/legs/{leg.pk}/tracks/").status_code == 403
    client.force_login(robot.user)
    assert "has no role" in client.get("/").content.decode()
    assert client.get(f"/gui/api/legs/{leg.pk}/tracks/").status_code == 403


def test_fleet_lists_logging_vehicles_to_anyone_with_a_role(client, leg, vehicle):
    assert client.get("/gui/api/fleet/").status_code in (401, 403)
    member(client, "vera", "viewer")
    assert client.get("/gui/api/fleet/").json() == {"vehicles": []}
    collector_for(vehicle, logging=True, leg=leg)
    segments.report_mode(leg, "ito")

    (entry,) = client.get("/gui/api/fleet/").json()["vehicles"]

    assert (entry["vehicle"]["key"], entry["mode"], entry["leg"]["id"]) == ("husky", "ito", leg.pk)


def test_the_fleet_view_carries_the_fleet_as_the_api_answers_it(client, leg, vehicle):
    """Opening the fleet view waits for no request: its vehicles come with the page."""
    member(client, "vera", "viewer")
    collector_for(vehicle, logging=True, leg=leg)
    segments.report_mode(leg, "ito")

    piece = _bootstrap(client.get("/?view=fleet").content.decode())["fleet"]

    assert piece == {"of": None, "data": client.get("/gui/api/fleet/").json()}
    assert [v["mode"] for v in piece["data"]["vehicles"]] == ["ito"]
    assert "fleet" not in _bootstrap(client.get(f"/?leg={leg.pk}").content.decode())


def _config(page: str) -> dict:
    config = re.search(r'<script id="gui-config" type="application/json">(.*?)</script>', page)
    return json.loads(config.group(1))


def _bootstrap(page: str) -> dict:
    return _config(page)["bootstrap"]


def _whole(client, path: str) -> list:
    page_size = _config(client.get("/").content.decode())["pageSize"]
    joiner = "&" if "?" in path else "?"
    answer = client.get(f"{path}{joiner}page_size={page_size}").json()
    return answer if isinstance(answer, list) else answer["results"]


def test_the_page_carries_its_first_reads_as_the_api_answers_them(client, leg, other_leg):
    segments.report_mode(leg, "auto")
    segments.new_manual_segment(leg)
    member(client, "otto", "operator")
    shift = leg.shift
    url = f"/?event={shift.test_event_id}&shift={shift.pk}&leg={leg.pk}"
    pieces = _bootstrap(client.get(url).content.decode())
    expected = {
        "reasons": (None, _whole(client, "/api/ito-reasons/")),
        "vehicles": (None, _whole(client, "/api/vehicles/")),
        "event": (None, _whole(client, "/api/test-events/")),
        "shift": (
            shift.test_event_id,
            _whole(client, f"/api/shifts/?test_event={shift.test_event_id}"),
        ),
        "leg": (shift.pk, _whole(client, f"/api/legs/?shift={shift.pk}")),
        "segments": (leg.pk, client.get(f"/gui/api/legs/{leg.pk}/segments/").json()),
    }
    assert {name: (p["of"], p["data"]) for name, p in pieces.items()} == expected
    assert len(pieces["segments"]["data"]["segments"]) == 3
    # The change feed's newest event then: the page's subscription catches up from it.
    newest = Announcement.objects.latest("id").pk
    assert _config(client.get(url).content.decode())["lastEventId"] == newest
    # The compare page asks for whole lists the same way.
    assert (
        _config(client.get("/compare/").content.decode())["pageSize"]
        == _config(client.get(url).content.decode())["pageSize"]
    )


def test_without_an_address_the_page_carries_the_logging_legs_reads(client, leg, vehicle):
    member(client, "vera", "viewer")
    # A process's first page loads its modules, which can take longer than a
    # collector stays online without a beat.
    assert "segments" not in _bootstrap(client.get("/").content.decode())
    collectors.heartbeat("field-1", vehicle=vehicle, logging=True, leg=leg)
    pieces = _bootstrap(client.get("/").content.decode())
    assert pieces["segments"]["of"] == leg.pk
    # A leg that is not the shift's is not carried: the page asks, and gets its 404.
    wrong = _bootstrap(client.get(f"/?event=1&shift={leg.shift_id}&leg=999999").content.decode())
    assert "segments" not in wrong
    member(client, "nobody")
    assert _bootstrap(client.get("/").content.decode()) == {}


def _opening(client, **cookies) -> dict | None:
    client.cookies.pop("ftt_cockpit", None)
    for name, value in cookies.items():
        client.cookies[name] = value
    return _config(client.get("/").content.decode())["opening"]


def test_a_bare_address_opens_the_last_cockpit_or_asks_which_robot(
    client, leg, other_leg, vehicle, other_vehicle
):
    member(client, "otto", "operator")
    assert _opening(client) is None
    logging = {"field-1": (vehicle, leg)}

    def opening(**cookies):
        # Collectors beat right before each look: a quiet one is not logging now.
        for name, (robot, into) in logging.items():
            collectors.heartbeat(name, vehicle=robot, logging=True, leg=into)
        return _opening(client, **cookies)

    mine = {"event": leg.shift.test_event_id, "shift": leg.shift_id, "leg": leg.pk}
    assert opening() == mine
    # Two robots logging into two legs: the page asks which (the fleet view lists them).
    logging["field-2"] = (other_vehicle, other_leg)
    assert opening() == {"view": "fleet"}
    # The cockpit this browser showed last wins, while its leg is there.
    other = {"event": other_leg.shift.test_event_id, "shift": other_leg.shift_id}
    other["leg"] = other_leg.pk
    shown = "{event}.{shift}.{leg}".format(**other)
    assert opening(ftt_cockpit=shown) == other
    # A last cockpit that no longer fits (another shift's leg, garbage) is not opened.
    wrong = f"{other['event']}.{leg.shift_id}.{other_leg.pk}"
    assert opening(ftt_cockpit=wrong) == {"view": "fleet"}
    assert opening(ftt_cockpit="1.2") == {"view": "fleet"}
    # An address that names something opens that, whatever the cookie says.
    page = client.get(f"/?event={leg.shift.test_event_id}")
    assert _config(page.content.decode())["opening"] is None
    # A robot that has gone quiet is not logging now: one leg left to open.
    del logging["field-2"]
    Collector.objects.filter(name="field-2").update(last_seen=timezone.now() - timedelta(hours=1))
    assert opening() == mine


def test_the_service_worker_is_served_from_the_sites_root(client):
    # Its scope is the folder it is served from: under /static/ it could not keep "/".
    answer = client.get("/sw.js")
    assert answer.status_code == 200
    assert answer["Content-Type"].startswith("text/javascript")
    assert b'addEventListener("fetch"' in answer.content
