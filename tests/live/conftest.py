import pytest

from tests.support import workers


@pytest.fixture(autouse=True)
def _quiet_heartbeat(settings):
    # The live tests read exact message sequences; the heartbeat has a test of its own.
    settings.FTT_LIVE_HEARTBEAT_MS = 3_600_000


REDIS_TEST_URL = workers.redis_url("redis://127.0.0.1:6379/7")


@pytest.fixture
def redis_layer(settings):
    """A Redis channel layer for this test (skipped without a Redis server); the
    client of its database, for the test's own checks."""
    redis = pytest.importorskip("redis")
    from channels.layers import channel_layers

    client = redis.Redis.from_url(REDIS_TEST_URL, socket_connect_timeout=0.5)
    try:
        client.ping()
    except redis.ConnectionError:
        pytest.skip("no Redis server on 127.0.0.1:6379")
    settings.REDIS_URL = REDIS_TEST_URL
    settings.CHANNEL_LAYERS = {
        "default": {
            "BACKEND": "channels_redis.pubsub.RedisPubSubChannelLayer",
            "CONFIG": {"hosts": [REDIS_TEST_URL]},
        }
    }
    channel_layers.backends.clear()
    yield client
    channel_layers.backends.clear()
