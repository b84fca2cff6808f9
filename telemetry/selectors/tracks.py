"""Tracks for the API: the poses of each master segment as one time-ordered line.

The points themselves come from ``reports.selectors.tracks.load_tracks`` so the
API, the GUI and the report agree on what a track is (time order, no-fix
points dropped); it reads raw floats with one query per kind of pose.
"""

from dataclasses import dataclass

import numpy as np
from django.db.models import QuerySet

from events.models import Segment
from reports.selectors.tracks import GPS, LOCAL, load_tracks


@dataclass
class SegmentTrack:
    segment: Segment
    x: np.ndarray
    y: np.ndarray
    frame: str = ""

    def __len__(self) -> int:
        return len(self.x)

    def coordinates(self) -> list[list[float]]:
        """[[x, y], ...] as plain floats, ready for JSON."""
        return np.column_stack((self.x, self.y)).tolist()


def masters(*, leg=None, shift=None, test_event=None) -> QuerySet[Segment]:
    """Master segments of one leg, shift or test event, oldest first."""
    queryset = Segment.objects.filter(parent__isnull=True)
    if leg is not None:
        queryset = queryset.filter(leg=leg)
    if shift is not None:
        queryset = queryset.filter(leg__shift=shift)
    if test_event is not None:
        queryset = queryset.filter(leg__shift__test_event=test_event)
    return queryset.order_by("start", "id")


def segment_tracks(segments: QuerySet[Segment], mode: str = GPS) -> list[SegmentTrack]:
    """One track per master that has usable points, in the masters' order.

    GPS tracks hold longitude (x) and latitude (y); local tracks map-frame metres.
    """
    segments = list(segments)
    loaded = load_tracks([s.pk for s in segments], mode)
    return [
        SegmentTrack(s, loaded[s.pk].x, loaded[s.pk].y, loaded[s.pk].frame)
        for s in segments
        if s.pk in loaded and len(loaded[s.pk])
    ]


__all__ = ["GPS", "LOCAL", "SegmentTrack", "masters", "segment_tracks"]
