"""What this test process keeps between reads: the tracks
(telemetry.selectors.cached_tracks) and the per-process memos (common.memo)."""

from common.api.authentication import known_tokens
from events.selectors import robots, segments
from telemetry.selectors import cached_tracks

# Every common.memo.Expiring of the code (tests/test_memos.py checks that none is missing).
MEMOS = (known_tokens, robots._bindings, segments._pose_targets)


def forget_cached_tracks() -> None:
    """Empties them, so that the next read is a fresh one."""
    with cached_tracks._lock:
        cached_tracks._cache.clear()


def forget_memos() -> None:
    """Tokens, robot bindings and segments cached per process belong to one test:
    ids are reused after a rolled-back test on SQLite."""
    for memo in MEMOS:
        memo.clear()
