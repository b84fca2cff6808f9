"""Small per-process caches for what a request would otherwise fetch every time.

Each web process keeps its own; a change made through this process clears its
entry at once (the owners connect signals), a change made elsewhere (another
worker, the admin in another process) is seen when the entry expires.  So
whatever is kept must be harmless for that long: the owner picks the time.
"""

import threading
import time
import weakref
from collections import OrderedDict

_every: weakref.WeakSet = weakref.WeakSet()


def clear_all() -> None:
    """Forget every kept entry of every cache (tests start from none)."""
    for memo in list(_every):
        memo.clear()


class Expiring:
    """A bounded mapping whose entries expire ``seconds`` after they were put."""

    def __init__(self, seconds: float, size: int = 4096):
        self.seconds = seconds
        self.size = size
        self._entries: OrderedDict = OrderedDict()
        # Web requests run in threads; the order of the entries is shared.
        self._lock = threading.Lock()
        _every.add(self)

    def get(self, key):
        """The value kept for ``key``, or None when absent or expired."""
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                return None
            if entry[0] < time.monotonic():
                del self._entries[key]
                return None
            return entry[1]

    def put(self, key, value) -> None:
        with self._lock:
            self._entries[key] = (time.monotonic() + self.seconds, value)
            self._entries.move_to_end(key)
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)

    def forget(self, key) -> None:
        with self._lock:
            self._entries.pop(key, None)

    def clear(self, *args, **kwargs) -> None:
        """Forget everything (also usable as a signal receiver)."""
        with self._lock:
            self._entries.clear()
