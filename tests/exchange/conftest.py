import pytest

from events.models import Performer, Personnel, PoseSource, TestEvent, Vehicle
from tests.support.snapshot import snapshot


@pytest.fixture
def wipe():
    """Forget everything, as on a freshly installed base station (catalogues stay)."""

    def _wipe():
        TestEvent.objects.all().delete()
        for model in (Vehicle, PoseSource, Performer, Personnel):
            model.objects.all().delete()
        assert all(not rows for rows in snapshot().values())

    return _wipe
