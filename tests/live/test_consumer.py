"""The websocket pushes feed rows to subscribed browsers and catches up reconnects."""

import asyncio
import contextlib

import pytest
import pytest_asyncio
from channels.db import database_sync_to_async
from channels.testing import WebsocketCommunicator
from django.contrib.auth.models import AnonymousUser, Group, User
from django.db import connections

from events.models import Announcement
from events.services import segments
from live import consumers, wakeup
from live.consumers import LiveConsumer
from rosbridge_app.selectors.fleet import fleet
from rosbridge_app.services import collectors
from telemetry.services import pose_writes

pytestmark = [
    pytest.mark.django_db(transaction=True),
    pytest.mark.asyncio,
]


@pytest_asyncio.fixture(autouse=True)
async def _close_the_worker_threads_connection():
    # The ORM calls above run in asgiref's worker thread, whose connection
    # (kept open by CONN_MAX_AGE) would otherwise outlive the test database.
    yield
    await database_sync_to_async(connections.close_all)()


@pytest.fixture(autouse=True)
def _no_links_left_open():
    # A test that ends without disconnecting leaves its links counted.
    yield
    consumers._OPEN_LINKS.clear()


@pytest.fixture
def viewer(db):
    user = User.objects.create_user("vera", password="pw")
    user.groups.add(Group.objects.get(name="viewer"))
    return user


async def connect(user, **subscribe):
    communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    communicator.scope["user"] = user
    connected, _ = await communicator.connect()
    assert connected
    await communicator.send_json_to({"type": "subscribe", **subscribe})
    reply = await communicator.receive_json_from(timeout=3)
    assert reply["type"] == "subscribed"
    return communicator, reply["last_id"]


async def next_events(communicator, timeout=2.0):
    message = await communicator.receive_json_from(timeout=timeout)
    assert message["type"] == "events"
    return message["events"]


async def test_user_without_role_is_refused(db):
    communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    communicator.scope["user"] = AnonymousUser()
    connected, code = await communicator.connect()
    assert not connected and code == 4403


async def test_new_segment_and_poses_arrive_without_asking(viewer, leg):
    # How fast is measured by benchmarks/live_latency.py; here: they arrive unasked.
    communicator, _ = await connect(viewer, leg=leg.pk)
    master = (await database_sync_to_async(segments.report_mode)(leg, "auto")).master
    await database_sync_to_async(pose_writes.store_poses)(master, [pose_writes.GpsFix(7.0, 50.0)])
    received = []
    while len(received) < 2:
        received += await next_events(communicator)
    assert [e["kind"] for e in received] == ["segment", "poses"]
    assert received[1]["payload"]["points"] == [[7.0, 50.0]]
    await communicator.disconnect()


async def test_a_mode_switch_brings_every_segment_it_changed(viewer, leg):
    ito = (await database_sync_to_async(segments.report_mode)(leg, "ito")).master
    communicator, _ = await connect(viewer, leg=leg.pk)
    auto = (await database_sync_to_async(segments.report_mode)(leg, "auto")).master
    (event,) = await next_events(communicator)
    rows = {row["id"]: row for row in event["segments"]}
    reason = await database_sync_to_async(lambda: ito.children.get().pk)()
    # The new AUTO master, and the ITO master and its reason it closed.
    assert set(rows) == {auto.pk, ito.pk, reason}
    assert rows[auto.pk]["is_open"] and not rows[ito.pk]["is_open"]
    assert rows[ito.pk]["end"] == rows[reason]["end"] == rows[auto.pk]["start"]
    labels = {int(k): v for k, v in event["labels"].items()}
    assert labels == {
        ito.pk: f"Leg {leg.number} · #1",
        reason: f"Leg {leg.number} · #1.1",
        auto.pk: f"Leg {leg.number} · #2",
    }
    await communicator.disconnect()


async def test_other_legs_poses_are_not_sent(viewer, leg, shift):
    from events.services import logs

    communicator, _ = await connect(viewer, leg=leg.pk)
    other = await database_sync_to_async(logs.create_leg)(shift=shift)  # closes `leg`
    events = await next_events(communicator)
    assert [e["kind"] for e in events] == ["log"]  # pickers hear about every level
    master = (await database_sync_to_async(segments.report_mode)(other, "ito")).master
    await database_sync_to_async(pose_writes.store_poses)(master, [pose_writes.GpsFix(7.0, 50.0)])
    assert await communicator.receive_nothing(timeout=0.8)
    await communicator.disconnect()


async def test_fleet_view_hears_every_legs_mode_and_gps_but_not_its_local_poses(
    viewer, leg, other_vehicle, test_event
):
    from events.services import logs

    other = await database_sync_to_async(
        lambda: logs.create_leg(
            shift=logs.create_shift(test_event=test_event, vehicle=other_vehicle)
        )
    )()
    communicator, _ = await connect(viewer, fleet=True)
    for robot_leg in (leg, other):
        master = (await database_sync_to_async(segments.report_mode)(robot_leg, "ito")).master
        await database_sync_to_async(pose_writes.store_poses)(
            master, [pose_writes.GpsFix(7.0, 50.0)]
        )
    received = []
    while len(received) < 4:
        received += await next_events(communicator)
    assert sorted((e["leg"], e["kind"]) for e in received) == sorted(
        (robot_leg.pk, kind) for robot_leg in (leg, other) for kind in ("segment", "poses")
    )
    await database_sync_to_async(pose_writes.store_local_poses)(
        master, [pose_writes.MapPose(1.0, 2.0, "map")]
    )
    assert await communicator.receive_nothing(timeout=0.8)
    await communicator.disconnect()


async def test_reconnecting_browser_gets_what_it_missed(viewer, leg):
    communicator, last_id = await connect(viewer, leg=leg.pk)
    await communicator.disconnect()
    await database_sync_to_async(segments.report_mode)(leg, "ito")
    again, _ = await connect_expecting_catch_up(viewer, leg.pk, last_id)
    assert [e["kind"] for e in again] == ["segment"]


async def connect_expecting_catch_up(user, leg_id, last_id):
    communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    communicator.scope["user"] = user
    await communicator.connect()
    await communicator.send_json_to({"type": "subscribe", "leg": leg_id, "last_id": last_id})
    events = await next_events(communicator)
    reply = await communicator.receive_json_from(timeout=2)
    assert reply["type"] == "subscribed"
    await communicator.disconnect()
    return events, reply


async def test_poller_waits_for_a_gap_before_skipping_it(viewer, leg, monkeypatch):
    poller = consumers.FeedReader()
    poller.floor = 10
    poller.seen = {12}
    poller._advance_floor()
    assert poller.floor == 10  # id 11 may still commit
    poller.gap_since -= consumers.GAP_PATIENCE + 1  # as if seen that much longer ago
    poller._advance_floor()
    assert poller.floor == 12 and not poller.seen


def first_poll(monkeypatch) -> asyncio.Event:
    """An event set once the poller has read the feed: a write after it can only
    reach the browser through a wake-up (or the next poll)."""
    polled = asyncio.Event()
    poll_once = consumers.FeedReader.poll_once

    async def noted(self):
        rows = await poll_once(self)
        polled.set()
        return rows

    monkeypatch.setattr(consumers.FeedReader, "poll_once", noted)
    return polled


async def test_with_redis_a_commit_wakes_the_poller_at_once(viewer, leg, redis_layer, monkeypatch):
    await _only_the_wakeup_delivers(viewer, leg, monkeypatch)


async def _only_the_wakeup_delivers(viewer, leg, monkeypatch):
    # Polling alone would take an hour: only a wake-up can deliver the event in time.
    monkeypatch.setattr(consumers, "POLL_INTERVAL", 3600.0)
    polled = first_poll(monkeypatch)
    communicator, _ = await connect(viewer, leg=leg.pk)
    await asyncio.wait_for(polled.wait(), 10)  # the poller now waits for a wake-up
    await database_sync_to_async(segments.report_mode)(leg, "auto")
    events = await next_events(communicator, timeout=5)
    assert [e["kind"] for e in events] == ["segment"]
    await communicator.disconnect()


async def test_a_commit_in_this_process_wakes_the_poller_at_once(viewer, leg, monkeypatch):
    await _only_the_wakeup_delivers(viewer, leg, monkeypatch)


@pytest.mark.postgis_only
async def test_on_postgresql_a_commit_anywhere_wakes_the_poller(viewer, leg, monkeypatch):
    # As if the writer were another process (the collector): no local call, no Redis.
    monkeypatch.setattr(wakeup, "_wake_local_readers", lambda: None)
    await _only_the_wakeup_delivers(viewer, leg, monkeypatch)


async def test_browser_away_longer_than_the_feed_keeps_is_told_to_reload(viewer, leg):
    await database_sync_to_async(segments.report_mode)(leg, "auto")
    await database_sync_to_async(segments.report_mode)(leg, "ito")
    newest = await database_sync_to_async(lambda: Announcement.objects.order_by("-id")[0].pk)()
    # Everything up to the newest row was pruned while the browser was away.
    await database_sync_to_async(lambda: Announcement.objects.filter(pk__lt=newest).delete())()
    communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    communicator.scope["user"] = viewer
    await communicator.connect()
    await communicator.send_json_to({"type": "subscribe", "leg": leg.pk, "last_id": 1})
    reply = await communicator.receive_json_from(timeout=2)
    assert reply == {"type": "reset", "last_id": newest}
    await communicator.disconnect()


async def test_an_idle_socket_hears_a_heartbeat_it_can_judge_the_link_by(viewer, settings):
    settings.FTT_LIVE_HEARTBEAT_MS = 100
    communicator, _ = await connect(viewer)
    beats = [await communicator.receive_json_from(timeout=1) for _ in range(3)]
    assert beats == [{"type": "heartbeat", "stale_after": 0.3}] * 3
    await communicator.disconnect()


def closing_socket(user):
    """A socket whose browser closes while being answered: like Uvicorn, sending
    then raises ClientDisconnected and the consumer's disconnect() is never called."""
    from uvicorn.protocols.utils import ClientDisconnected

    closed = asyncio.Event()

    async def app(scope, receive, send):
        async def send_or_fail(message):
            if closed.is_set():
                raise ClientDisconnected
            await send(message)

        await LiveConsumer.as_asgi()(scope, receive, send_or_fail)

    communicator = WebsocketCommunicator(app, "/ws/live/")
    communicator.scope["user"] = user
    return communicator, closed


async def test_sockets_closed_while_subscribing_leave_and_the_others_get_every_row(
    viewer, leg, caplog
):
    fleet, last_id = await connect(viewer, fleet=True)
    await database_sync_to_async(segments.report_mode)(leg, "auto")
    assert [e["kind"] for e in await next_events(fleet)] == ["segment"]
    closing = []
    for _ in range(5):
        communicator, closed = closing_socket(viewer)
        assert (await communicator.connect())[0]
        closed.set()  # the browser goes as its old last_id is answered
        await communicator.send_json_to({"type": "subscribe", "fleet": True, "last_id": last_id})
        closing.append(communicator)
    poller = consumers.FeedReader.for_loop()
    for communicator in closing:
        with contextlib.suppress(OSError):  # Uvicorn swallows what the app raises
            await communicator.wait(timeout=2)  # the consumer has ended
    assert len(poller.consumers) == 1
    master = await database_sync_to_async(lambda: leg.segments.get(end__isnull=True))()
    for i in range(20):
        await database_sync_to_async(pose_writes.store_poses)(
            master, [pose_writes.GpsFix(7.0 + i / 1000, 50.0)]
        )
    received = []
    while len(received) < 20:
        received += await next_events(fleet)
    assert [e["kind"] for e in received] == ["poses"] * 20
    assert not [r for r in caplog.records if r.levelname in ("ERROR", "CRITICAL")]
    await fleet.disconnect()


async def test_a_fleet_view_gets_each_vehicles_entry_as_the_fleet_read_gives_it(viewer, leg):
    vehicle = await database_sync_to_async(lambda: leg.shift.vehicle)()
    await database_sync_to_async(collectors.heartbeat)(
        "rover-collector", vehicle=vehicle, logging=True, leg=leg
    )
    communicator, _ = await connect(viewer, fleet=True)
    master = (await database_sync_to_async(segments.report_mode)(leg, "ito")).master
    await database_sync_to_async(pose_writes.store_poses)(master, [pose_writes.GpsFix(7.0, 50.0)])
    received = []
    while len(received) < 2:
        received += await next_events(communicator)
    (entry,) = await database_sync_to_async(fleet)()
    assert [e["kind"] for e in received] == ["segment", "poses"]
    # Each row carries the entry as the fleet read gives it when the row is read.
    assert received[0]["fleet"]["vehicle"]["id"] == vehicle.pk
    assert received[0]["fleet"]["mode"] == "ito"
    assert received[1]["fleet"] == entry
    assert (entry["mode"], entry["position"]) == ("ito", [50.0, 7.0])
    await communicator.disconnect()


async def test_an_account_holds_a_bounded_number_of_live_links(viewer, settings):
    settings.FTT_LIVE_LINKS_PER_ACCOUNT = 3
    links = [(await connect(viewer))[0] for _ in range(3)]
    refused = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    refused.scope["user"] = viewer
    connected, code = await refused.connect()
    assert not connected and code == 4429
    await links.pop().disconnect()
    again, _ = await connect(viewer)
    for link in [*links, again]:
        await link.disconnect()
