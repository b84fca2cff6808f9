"""The distance of a master segment: the one rule every figure uses.

The measured polyline is [start position] + the segment's poses in time order
+ [start position of the next master in the same leg].  GPS: geodesic on the
WGS84 ellipsoid; local: planar in map metres.  The joins make the distances
of consecutive segments add up to the distance driven, with no metre lost at
a mode switch.  A segment without poses still gets the straight join from its
start to the next start when both are known.

The GUI's segment list, the API, the statistics, the report and the exports
all read distances from here.
"""

from collections.abc import Iterable
from dataclasses import dataclass, field

from events.models import Segment
from telemetry.selectors.tracks import GPS, LOCAL, Track, load_tracks, path_length


@dataclass
class MeasuredPath:
    """The polyline a master segment's distance was measured on."""

    segment_id: int
    distance: float | None
    track: Track | None
    has_start_position: bool
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)


def start_point(segment: Segment, mode: str) -> tuple[float, float] | None:
    if mode == GPS:
        p = segment.start_position
        return (p.x, p.y) if p is not None else None
    if segment.start_local_x is None:
        return None
    return (segment.start_local_x, segment.start_local_y)


def measured_paths(
    masters: Iterable[Segment], mode: str = GPS, tracks: dict[int, Track] | None = None
) -> dict[int, MeasuredPath]:
    """Paths of the given master segments, keyed by id.

    The next master of each is looked up among the given ones of the same
    leg, so pass whole legs.  ``distance`` is None when fewer than two points
    are known: nothing was measured, which is not the same as standing still.
    """
    masters = sorted(masters, key=lambda m: (m.leg_id, m.start, m.pk))
    if tracks is None:
        tracks = load_tracks([m.pk for m in masters], mode)
    paths = {}
    for i, master in enumerate(masters):
        follower = masters[i + 1] if i + 1 < len(masters) else None
        if follower is not None and follower.leg_id != master.leg_id:
            follower = None
        track = tracks.get(master.pk)
        xs, ys = ([], []) if track is None else (list(track.x), list(track.y))
        start = start_point(master, mode)
        if start is not None:
            xs.insert(0, start[0])
            ys.insert(0, start[1])
        after = start_point(follower, mode) if follower is not None else None
        if after is not None:
            xs.append(after[0])
            ys.append(after[1])
        paths[master.pk] = MeasuredPath(
            segment_id=master.pk,
            distance=path_length(xs, ys, mode) if len(xs) > 1 else None,
            track=track,
            has_start_position=start is not None,
            x=xs,
            y=ys,
        )
    return paths


def displayed_distances(
    masters: list[Segment],
    gps: dict[int, Track] | None = None,
    local: dict[int, Track] | None = None,
) -> dict[int, float | None]:
    """What a list shows for one leg's masters: the GPS distance where one was
    measured, else the local one, else None (nothing measured)."""
    by_gps = measured_paths(masters, GPS, gps)
    by_local = measured_paths(masters, LOCAL, local)
    return {
        pk: path.distance if path.distance is not None else by_local[pk].distance
        for pk, path in by_gps.items()
    }
