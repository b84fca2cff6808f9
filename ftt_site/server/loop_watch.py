"""A watch on the web worker's event loop.

Every page, API call and websocket of a worker waits on its one event loop.
Code that blocks the loop stops them all; the supervisor notices only after
its timeout (two minutes) and replaces the worker without saying why.  The
watch asks the loop to run a no-op every second from a thread of its own; when
the loop has not run it for ``FTT_LOOP_STALL_S`` seconds the watch logs once,
with the stack of every thread, the blocking one among them.  The server
starts it through the ASGI lifespan protocol (:func:`lifespan`).
"""

import asyncio
import faulthandler
import logging
import os
import sys
import threading
import time

log = logging.getLogger("ftt.web")

STALL_S = float(os.environ.get("FTT_LOOP_STALL_S") or 10)
ASK_EVERY_S = 1.0


def watch_loop(loop, stall_s: float = STALL_S, file=None) -> threading.Thread:
    """Start watching ``loop``; the stacks go to ``file`` (a real file: the
    dump is written without Python's help), by default standard error."""

    def watch():
        answered = threading.Event()
        while not loop.is_closed():
            answered.clear()
            try:
                loop.call_soon_threadsafe(answered.set)
            except RuntimeError:
                return
            if not answered.wait(stall_s):
                log.error(
                    "The event loop has run nothing for %.0f s; every thread's stack follows.",
                    stall_s,
                )
                faulthandler.dump_traceback(file=file or sys.stderr, all_threads=True)
                # Once per stall: the next word is when it ends.
                started = time.monotonic() - stall_s
                while not answered.wait(ASK_EVERY_S):
                    if loop.is_closed():
                        return
                log.error("The event loop runs again after %.0f s.", time.monotonic() - started)
            time.sleep(ASK_EVERY_S)

    thread = threading.Thread(target=watch, name="loop-watch", daemon=True)
    thread.start()
    return thread


async def lifespan(scope, receive, send) -> None:
    """The ASGI application of the lifespan protocol: the watch starts with the
    server's event loop."""
    while True:
        message = await receive()
        if message["type"] == "lifespan.startup":
            watch_loop(asyncio.get_running_loop())
            await send({"type": "lifespan.startup.complete"})
        elif message["type"] == "lifespan.shutdown":
            await send({"type": "lifespan.shutdown.complete"})
            return
