import pytest


@pytest.fixture(autouse=True)
def _quiet_heartbeat(settings):
    # The live tests read exact message sequences; the heartbeat has a test of its own.
    settings.FTT_LIVE_HEARTBEAT_MS = 3_600_000
