from events.models.catalogues import ItoReason, SegmentType, Weather
from events.models.configuration import Performer, Personnel, PoseSource, Vehicle
from events.models.feed import Announcement
from events.models.hierarchy import Leg, Segment, Shift, TestEvent
from events.models.notes import Note
from events.models.plans import Criterion, Judgement, TestCase
from events.models.robots import RobotAccount

__all__ = [
    "Announcement",
    "Criterion",
    "ItoReason",
    "Judgement",
    "Leg",
    "Note",
    "Performer",
    "Personnel",
    "PoseSource",
    "RobotAccount",
    "Segment",
    "SegmentType",
    "TestCase",
    "Shift",
    "TestEvent",
    "Vehicle",
    "Weather",
]
