"""Segments as a robot's mode reports open them."""

from events.models import Segment, SegmentType
from events.services import segments


def start_auto(leg, **report) -> Segment:
    """Report AUTO on ``leg`` as a robot does; returns the master segment it opened."""
    return segments.report_mode(leg, SegmentType.AUTO, **report).master
