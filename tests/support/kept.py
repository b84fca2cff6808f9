"""The tracks this test process keeps between reads (telemetry.selectors.kept_tracks)."""

from telemetry.selectors import kept_tracks


def forget_kept_tracks() -> None:
    """Empties them, so that the next read is a fresh one."""
    with kept_tracks._lock:
        kept_tracks._kept.clear()
