"""Tracks cached between the map's reads in each web process.

The map asks for a leg's tracks at every visit, zoom and live update; a track
read before is used again while its segment is unchanged (``cached_tracks``).
"""

import threading

from cachetools import LRUCache
from django.db.models import Count, Max, Value

from events.models import Segment
from telemetry.models import LocalPose, Pose
from telemetry.selectors.tracks import Track, load_tracks
from telemetry.storage.keys import GPS_TRACK, TRACK_KINDS

# {(mode, segment id): (key, track)}, bounded in points (x, y and t: 24 bytes
# each, so about 100 MB), least recently read dropped first.
_cache: LRUCache = LRUCache(maxsize=4_000_000, getsizeof=lambda entry: len(entry[1]))
_lock = threading.Lock()


def _cached_for(slot: tuple[str, int], key: tuple) -> Track | None:
    """The track cached in ``slot`` if it was read for ``key``."""
    with _lock:
        entry = _cache.get(slot)
    return entry[1] if entry is not None and entry[0] == key else None


def _remember(slot: tuple[str, int], key: tuple, track: Track) -> None:
    with _lock:
        _cache.pop(slot, None)
        if len(track) <= _cache.maxsize:
            _cache[slot] = (key, track)


# Held while tracks that are not cached are read, so a request that arrives
# during a read ahead of the same leg (gui.views.gui_api.read_ahead) waits for
# it and takes its tracks instead of reading them a second time.
_reading = threading.Lock()


def pose_counts(
    segment_ids: list[int], modes=TRACK_KINDS
) -> dict[tuple[str, int], tuple[int, int]]:
    """{(mode, segment id): (poses stored, newest pose id)} of the segments
    that have poses, in one query (an index-only count on PostgreSQL)."""
    parts = [
        (Pose if mode == GPS_TRACK else LocalPose)
        .objects.filter(segment_id__in=segment_ids)
        .values("segment_id")
        .annotate(_n=Count("id"), _newest=Max("id"), _mode=Value(mode))
        .values_list("_mode", "segment_id", "_n", "_newest")
        .order_by()
        for mode in modes
    ]
    if not segment_ids or not parts:
        return {}
    rows = parts[0].union(*parts[1:], all=True) if len(parts) > 1 else parts[0]
    return {(mode, seg): (n, newest) for mode, seg, n, newest in rows}


def cached_tracks(segments: list[Segment], modes=TRACK_KINDS) -> dict[str, dict[int, Track]]:
    """``load_tracks`` of each mode for the map, which asks again at every
    visit, zoom and live update: {mode: {segment id: track}}.

    A track read before in this process is used again while its segment's
    count of poses and newest pose id are unchanged.  Poses are only ever
    added (a late batch from a collector's spool may still arrive for a closed
    segment) and deleted with their segment, and every added pose raises the
    count, so a changed track is always read again; its segment's uid tells it
    from an older segment that had the same id (a database restored under a
    running server).  Two queries at most per mode, however many segments."""
    by_id = {s.pk: s for s in segments}
    counts = pose_counts(list(by_id), modes)
    found: dict[str, dict[int, Track]] = {mode: {} for mode in modes}
    if _take_cached(found, by_id, counts):
        return found
    with _reading:
        if _take_cached(found, by_id, counts):
            return found
        for mode, tracks in found.items():
            ids = [seg for (m, seg) in counts if m == mode and seg not in tracks]
            if not ids:
                continue
            # A pose stored after the count was taken is in the track read now and
            # changes the count again, so the next read replaces this one.
            read = load_tracks(ids, mode)
            tracks.update(read)
            for seg, track in read.items():
                key = (by_id[seg].uid, *counts[mode, seg])
                # What the track was read for, so results derived from it can be cached too.
                track.memo["kept"] = (mode, *key)
                _remember((mode, seg), key, track)
    return found


def _take_cached(found: dict[str, dict[int, Track]], by_id: dict, counts: dict) -> bool:
    """Puts the cached tracks of ``counts`` into ``found``; True when all were cached."""
    complete = True
    for (mode, seg), count in counts.items():
        if seg in found[mode]:
            continue
        track = _cached_for((mode, seg), (by_id[seg].uid, *count))
        if track is None:
            complete = False
        else:
            found[mode][seg] = track
    return complete


def caches_any(segments: list[Segment]) -> bool:
    """Whether this process caches a track of any of ``segments``, current or
    not (no query: what ``cached_tracks`` would then read is what changed)."""
    with _lock:
        return any((mode, s.pk) in _cache for mode in TRACK_KINDS for s in segments)
