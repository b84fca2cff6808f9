"""Robot data on the open leg of the shared fixtures."""

import pytest

from events.models import SegmentType
from events.services import segments


@pytest.fixture
def auto_master(leg):
    return segments.report_mode(leg, SegmentType.AUTO).master
