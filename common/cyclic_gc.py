"""Python's cyclic garbage collector, paused around work that builds many
short-lived objects without cycles, which reference counting frees anyway.

A campaign's comparison builds a row per segment; the collector's passes
over them free nothing (docs/report.md has the figures). The pause is
process-wide, so it is counted: the collector runs again when the last of
the threads that paused it (web requests run in threads) is done,
and stays off if it was off before.
"""

import gc
import threading
from collections.abc import Iterator
from contextlib import contextmanager

_lock = threading.Lock()
_pausing = 0
_was_enabled = True


@contextmanager
def paused() -> Iterator[None]:
    """Usable as ``with paused():`` or as a decorator."""
    global _pausing, _was_enabled
    with _lock:
        if _pausing == 0:
            _was_enabled = gc.isenabled()
            gc.disable()
        _pausing += 1
    try:
        yield
    finally:
        with _lock:
            _pausing -= 1
            if _pausing == 0 and _was_enabled:
                gc.enable()
