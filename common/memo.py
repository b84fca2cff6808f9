"""Small per-process caches for what a request would otherwise fetch every time.

Each web process keeps its own; a change made through this process clears its
entry at once (the owners connect signals), a change made elsewhere (another
worker, the admin in another process) is seen when the entry expires.  So
whatever is kept must be harmless for that long: the owner picks the time.
"""

import threading

from cachetools import TTLCache


class Expiring:
    """A bounded mapping whose entries expire ``seconds`` after they were put:
    cachetools' TTLCache behind a lock (web requests run in threads, and
    TTLCache is not thread-safe)."""

    def __init__(self, seconds: float, size: int = 4096):
        self._entries = TTLCache(maxsize=size, ttl=seconds)
        self._lock = threading.Lock()

    def get(self, key):
        """The value kept for ``key``, or None when absent or expired."""
        with self._lock:
            return self._entries.get(key)

    def put(self, key, value) -> None:
        with self._lock:
            self._entries[key] = value

    def forget(self, key) -> None:
        with self._lock:
            self._entries.pop(key, None)

    def clear(self, *args, **kwargs) -> None:
        """Forget everything (also usable as a signal receiver)."""
        with self._lock:
            self._entries.clear()
