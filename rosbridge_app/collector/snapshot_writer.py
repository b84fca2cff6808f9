"""The child process that writes snapshot files, and the collector's side of it.

Building an MCAP file is Python work that would hold the interpreter lock the
collector's executor and database writer need, so a child process builds the
files; the collector hands it the messages through memory files (a few
wake-ups per window) and waits for a bounded time.  docs/collector.md
("Black-box snapshots") says why each piece is as it is.
"""

import atexit
import logging
import multiprocessing
import os
import signal
import tempfile
import threading
import traceback
from multiprocessing import reduction
from pathlib import Path

from django.utils.translation import gettext

from rosbridge_app.collector.mcap_files import McapFile, MessageDefinitions, part_path

log = logging.getLogger("ftt.collector")

MB = 1024 * 1024
# Bytes handed to the writer process at a time (one memory file each): a 20 s
# window of the benchmark robot is one piece, and a 200 MB window never lies in
# memory twice.
PIECE = 32 * MB
# A new writer process must be ready (interpreter, mcap, type store) within this;
# a few seconds on a loaded machine.
START_TIMEOUT = 120.0
WRITER_NICE = 10  # where SCHED_IDLE is not to be had

# The writer process's definitions: it keeps them from one snapshot to the next.
_definitions = MessageDefinitions()


def _serve(conn) -> None:
    """The writer process: files from requests on ``conn`` until the collector
    closes it or is gone (end of file either way).  Ctrl-C and SIGTERM reach the
    whole process group: the collector decides when its writer ends (it writes
    the open windows at exit).  SCHED_IDLE (niced where not available): on a
    busy machine the collector's own threads come first, a file may well be
    written a second later."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    _step_aside()
    _definitions.load()  # at the trigger, not when the window has passed
    conn.send(("ready", None))
    mcap, failed = None, None
    while True:
        try:
            op, arg = conn.recv()
            window = reduction.recv_handle(conn) if op == "add" else None
        except (EOFError, ConnectionResetError):
            return  # a collector that stops may reset the pipe rather than close it
        try:
            if op == "begin":
                if mcap is not None:  # the collector gave up on it
                    mcap.abandon()
                failed, mcap = None, None
                mcap = McapFile(Path(arg[0]), arg[1], _definitions)
            elif op == "add":
                try:
                    if failed is None:
                        mcap.add(read_window(window, arg))
                finally:
                    os.close(window)
                    conn.send(("added", None))
            elif op == "finish":
                if failed is not None:
                    conn.send(("error", failed))
                else:
                    conn.send(("done", mcap.finish()))
                mcap = None
        except Exception:
            failed = traceback.format_exc()
            if mcap is not None:
                mcap.abandon()
                mcap = None


def _step_aside() -> None:
    """Run only on a core that nothing else wants (SCHED_IDLE), where Linux
    has it; niced otherwise."""
    try:
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    except (AttributeError, OSError):
        os.nice(WRITER_NICE)


def window_file(messages: list) -> tuple[int, list]:
    """(descriptor of a memory file holding the messages' bytes one after the
    other, index [(t_ns, topic, length)]).  ``writev`` copies them in a few
    system calls, which release the interpreter lock."""
    if hasattr(os, "memfd_create"):
        fd = os.memfd_create("ftt-snapshot-window", os.MFD_CLOEXEC)
    else:
        fd = os.dup((f := tempfile.TemporaryFile()).fileno())
        f.close()
    try:
        datas = [m[2] for m in messages]
        step = os.sysconf("SC_IOV_MAX")
        for i in range(0, len(datas), step):
            chunk = datas[i : i + step]
            written = os.writev(fd, chunk)
            if written < sum(map(len, chunk)):  # a short write (rare): the rest
                rest = memoryview(b"".join(chunk))[written:]
                while rest:
                    rest = rest[os.write(fd, rest) :]
        return fd, [(t, topic, len(data)) for t, topic, data in messages]
    except BaseException:
        os.close(fd)
        raise


def read_window(fd: int, index: list) -> list:
    """The messages (t_ns, topic, bytes) of a :func:`window_file`."""
    out, offset = [], 0
    for t, topic, length in index:
        out.append((t, topic, os.pread(fd, length, offset)))
        offset += length
    return out


def pieces(messages: list, size: int) -> list[list]:
    """Consecutive slices of messages (t_ns, topic, bytes) of about ``size`` bytes."""
    out, start, total = [], 0, 0
    for i, message in enumerate(messages):
        total += len(message[2])
        if total >= size:
            out.append(messages[start : i + 1])
            start, total = i + 1, 0
    if start < len(messages):
        out.append(messages[start:])
    return out


class WriterDied(Exception):
    pass


class SnapshotError(Exception):
    """The writer process could not write a file (and is still there)."""


class WriterChild:
    """One writer process and the collector's end of its pipe."""

    def __init__(self):
        context = multiprocessing.get_context("spawn")
        self.conn, theirs = context.Pipe()
        self.process = context.Process(
            target=_serve, args=(theirs,), name="ftt-snapshot-writer", daemon=False
        )
        self.process.start()
        theirs.close()  # so that its death is an end of file here
        self.pid = self.process.pid
        self.ready = False
        self.stuck = ""  # why the watchdog killed it

    def kill(self) -> None:
        self.process.kill()

    def close(self, wait: float) -> None:
        self.conn.close()  # its end of file: it returns
        self.process.join(wait)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(5)


class WriterProcess:
    """The child process that writes snapshot files, started by the first
    trigger and kept.  'spawn': the collector has DDS threads running, and a
    forked copy of them is undefined; a spawned interpreter imports this module
    and the mcap library only.  If it dies (killed, out of memory) or is stuck
    (alive but not done within its time), the collector logs it, kills it and
    starts a new one for the next file."""

    def __init__(self):
        self._child: WriterChild | None = None
        self._lock = threading.Lock()
        self._given_up = False

    @property
    def pid(self) -> int | None:
        child = self._child
        return child.pid if child is not None else None

    def start(self) -> WriterChild:
        """The running writer, started if needed (without waiting for it to be ready)."""
        with self._lock:
            old = self._child
            if old is not None and not old.process.is_alive():
                log.error(
                    gettext("the snapshot writer process (pid %d) died; starting a new one"),
                    old.pid,
                )
                old.close(wait=0)
                self._child = None
            if self._child is None:
                self._child = WriterChild()
                log.info(gettext("snapshot writer process started (pid %d)"), self._child.pid)
                # multiprocessing joins its children at exit: a writer whose pipe
                # is still open would keep the collector from ever exiting.
                atexit.unregister(self.close)
                atexit.register(self.close)
            return self._child

    def write(self, path: Path, messages: list, types: dict[str, str], timeout: float) -> dict:
        """Write the file in the child, which must be done within ``timeout``
        seconds once it runs; a child that dies or is stuck gets one successor
        to try again."""
        for attempt in (1, 2):
            if self._given_up:
                raise WriterDied(f"the collector stopped before {path.name} was written")
            child = self.start()
            try:
                return self._write(child, path, messages, types, timeout)
            except (OSError, EOFError):
                if self._given_up:
                    stopped = f"the collector stopped before {path.name} was written"
                    raise WriterDied(stopped) from None
                what = f"was stuck ({child.stuck}) and was killed" if child.stuck else "died"
                log.error(
                    gettext("the snapshot writer process (pid %s) %s before it finished %s; %s"),
                    child.pid,
                    what,
                    path.name,
                    "starting a new one to try again" if attempt == 1 else "snapshot lost",
                )
                child.kill()
                # Half a file, or a whole one it had no time to report: the
                # successor writes it again, or nothing is delivered.
                part_path(path).unlink(missing_ok=True)
                path.unlink(missing_ok=True)
                with self._lock:
                    if self._child is child:
                        self._child = None
                child.close(wait=5)
        raise WriterDied(f"the snapshot writer failed twice while writing {path.name}")

    def _write(self, child: WriterChild, path: Path, messages, types, timeout: float) -> dict:
        conn = child.conn
        if not child.ready:
            # Starting an interpreter and loading the type store: seconds on a
            # loaded machine, not part of the file's time.
            self._within(child, START_TIMEOUT, "not ready", conn.recv)
            child.ready = True
        work = lambda: self._exchange(conn, child.pid, path, messages, types)  # noqa: E731
        return self._within(child, timeout, "not done", work)

    @staticmethod
    def _exchange(conn, child_pid: int, path: Path, messages, types) -> dict:
        conn.send(("begin", (str(path), types)))
        for piece in pieces(messages, PIECE):
            fd, index = window_file(piece)
            try:
                conn.send(("add", index))
                reduction.send_handle(conn, fd, child_pid)
            finally:
                os.close(fd)
            conn.recv()  # taken: the next piece (so at most one is in memory twice)
        conn.send(("finish", None))
        status, result = conn.recv()
        if status == "error":
            raise SnapshotError(
                gettext("the writer process could not write %(file)s:\n%(error)s")
                % {"file": path.name, "error": result}
            )
        return result

    @staticmethod
    def _within(child: WriterChild, seconds: float, what: str, work):
        """Run ``work``; a child not done by then is killed, which ends whatever
        ``work`` waits for (a full pipe, a reply) with an OSError or EOFError."""

        def stuck() -> None:
            child.stuck = f"{what} after {seconds:.0f} s"
            child.kill()

        watchdog = threading.Timer(seconds, stuck)
        watchdog.daemon = True
        watchdog.start()
        try:
            return work()
        finally:
            watchdog.cancel()

    def give_up(self) -> None:
        """Kill the writer now and start no other (the collector is stopping)."""
        self._given_up = True
        child = self._child
        if child is not None:
            child.stuck = "the collector stopped"
            child.kill()

    def close(self) -> None:
        atexit.unregister(self.close)
        with self._lock:
            child, self._child = self._child, None
        if child is not None:
            child.close(wait=30)
