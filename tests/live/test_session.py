"""The live websocket ends with the session it was opened in, and survives junk frames."""

import pytest
import pytest_asyncio
from channels.db import database_sync_to_async
from channels.testing import WebsocketCommunicator
from django.contrib.auth.models import Group, User
from django.db import connections
from django.test import Client

from live import consumers
from live.consumers import LiveConsumer

pytestmark = [pytest.mark.django_db(transaction=True), pytest.mark.asyncio]


@pytest_asyncio.fixture(autouse=True)
async def _close_the_worker_threads_connection():
    yield
    await database_sync_to_async(connections.close_all)()


@pytest.fixture
def browser(db):
    """A viewer signed in through the login page, and the session its websocket carries."""
    from django.contrib.sessions.backends.db import SessionStore

    user = User.objects.create_user("vera", password="pw-long-enough-1")
    user.groups.add(Group.objects.get(name="viewer"))
    client = Client()
    client.force_login(user)
    session = SessionStore(client.session.session_key)
    session.load()
    return client, user, session


async def opened(user, session):
    communicator = WebsocketCommunicator(LiveConsumer.as_asgi(), "/ws/live/")
    communicator.scope["user"] = user
    communicator.scope["session"] = session
    connected, _ = await communicator.connect()
    assert connected
    return communicator


async def test_a_session_that_ends_without_a_logout_closes_at_the_next_check(browser, monkeypatch):
    monkeypatch.setattr(consumers, "SESSION_CHECK_INTERVAL", 0.2)
    _, user, session = browser
    communicator = await opened(user, session)
    # Expired and cleared (clearsessions), or deleted by an administrator: no signal.
    await database_sync_to_async(session.delete)()
    message = await communicator.receive_json_from(timeout=3)
    assert message["type"] == "error" and "sign in again" in message["detail"]
    assert (await communicator.receive_output(timeout=3))["code"] == 4401


async def test_logout_tells_the_websocket_at_once(browser):
    """Not at the socket's next periodic check (30 s): the logout tells the live layer."""
    client, user, session = browser
    communicator = await opened(user, session)
    await database_sync_to_async(client.post)("/logout/")
    message = await communicator.receive_json_from(timeout=2)
    assert message["type"] == "error" and "sign in again" in message["detail"]
    assert (await communicator.receive_output(timeout=1))["code"] == 4401


async def test_losing_the_role_closes_the_websocket_on_the_next_subscribe(browser):
    _, user, session = browser
    communicator = await opened(user, session)
    await database_sync_to_async(user.groups.clear)()
    await communicator.send_json_to({"type": "subscribe"})
    assert (await communicator.receive_json_from(timeout=3))["type"] == "error"
    assert (await communicator.receive_output(timeout=3))["code"] == 4401


async def test_malformed_frames_get_an_error_and_the_socket_stays_usable(browser):
    _, user, session = browser
    communicator = await opened(user, session)
    for frame in ("[1, 2]", "42", "not json", '"subscribe"', "null"):
        await communicator.send_to(text_data=frame)
        reply = await communicator.receive_json_from(timeout=3)
        assert reply == {"type": "error", "detail": "Send one JSON object."}
    await communicator.send_json_to({"type": "subscribe"})
    assert (await communicator.receive_json_from(timeout=3))["type"] == "subscribed"
    await communicator.disconnect()
