"""Threads of ``manage.py ftt_collect``.

* ROS thread: one SingleThreadedExecutor spinning :class:`CollectorNode`;
  callbacks put events on an in-memory queue and return.
* Spool thread: renders pictures (PNG/JPEG) and appends events to the
  :class:`Spool` on disk, a few times a second.
* Main thread: the only one that talks to the database: applies spool events
  in order through :class:`EventWriter`, beats, takes GUI commands, follows the
  vehicle's leg.  When the database is unreachable it says so once, backs off
  and retries; the spool keeps growing meanwhile and is replayed in order.

SIGINT/SIGTERM (rclpy's handlers) stop the ROS thread; then the queue is
spooled, the spool is written to the database if it can be, and the process
exits.  A SIGKILL loses only what was still in memory (< ~0.1 s of data).

A collector whose node hears nothing while others publish (deaf_watch.py) and
whose re-created subscriptions did not help either renews itself: the same
clean stop, then the process executes itself again (same pid, new DDS
participant), resuming its logging state from the spool.

DDS transport: the collector receives over UDP only
(``FASTDDS_BUILTIN_TRANSPORTS=UDPv4`` unless set otherwise), which holds no
state a crash can leave behind: Fast DDS's shared-memory ports outlive a
SIGKILL, and publishers that still hold a dead port keep writing into it
(docs/collector.md, "Nothing is lost").
"""

import logging
import os
import queue
import socket
import sys
import threading
import time
from pathlib import Path

import rclpy
from django.db import InterfaceError, OperationalError, close_old_connections, connections
from django.utils import timezone
from django.utils.translation import gettext
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter

from events import feed
from events.models import Vehicle
from events.selectors.logs import open_leg_for_vehicle
from rosbridge_app.collector.disk_guard import FULL, DiskGuard
from rosbridge_app.collector.event_writer import DatabaseUnavailable, EventWriter
from rosbridge_app.collector.node import CollectorNode
from rosbridge_app.collector.replay import ReplayOrder
from rosbridge_app.collector.spool import Spool, SpoolFull
from rosbridge_app.collector.spooler import Spooler, default_spool
from rosbridge_app.collector.status import Status
from rosbridge_app.models import CollectorCommand
from rosbridge_app.services import collectors as link

log = logging.getLogger("ftt.collector")

# Records the writer takes from the spool per transaction: a backlog after an
# outage is replayed in few large bulk inserts (benchmarks/collector_endurance.py),
# and a live mode switch waits for at most one such slice (collector/replay.py).
WRITE_BATCH = 2000
HEARTBEAT = 1.0
COMMAND_POLL = 0.25
SYNC = 1.0
# A spool that is full is tried again after RETRY; a database that is away after
# RECONNECT: a refused connection costs a millisecond, and live data must be
# stored within 2 s of the database's return.
RETRY = 1.0
RECONNECT = 0.25
EXIT_FLUSH_SECONDS = 10.0
# Slices the writer stores at most, ahead of its chores, to reach a segment change.
URGENT_SLICES = 4
# Live positions are stored at most this often, so that a robot publishing at
# 10-100 Hz pays for a few transactions a second, not one per message; a
# segment change and a backlog do not wait (docs/collector.md, "Pace").
PACE = 0.2
# Pending snapshots may take this long at exit; a stuck writer is killed then.
EXIT_SNAPSHOT_SECONDS = 10.0
# A renewed collector that is deaf again renews no sooner than this: it keeps
# re-creating its subscriptions instead of restarting in a loop.
RENEW_AT_MOST_EVERY_S = 300.0
RENEWED_ENV = "FTT_COLLECT_RENEWED_AT"


def process_started() -> float:
    """Wall-clock time this process was started (before the ROS wheels' re-exec)."""
    try:
        fields = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        boot = next(
            float(line.split()[1])
            for line in Path("/proc/stat").read_text().splitlines()
            if line.startswith("btime")
        )
        return boot + int(fields[19]) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return time.time()


class StartupTimes:
    """Where a collector's start-up goes, logged once with its first stored record
    (benchmarks/collector_startup.py reads the line)."""

    def __init__(self):
        self.marks = [("process start", process_started())]
        self.reported = False

    def mark(self, label: str) -> None:
        if not self.has(label):
            self.marks.append((label, time.time()))

    def has(self, label: str) -> bool:
        return any(name == label for name, _ in self.marks)

    def line(self) -> str:
        steps = [
            f"{label} +{t - before:.2f} s"
            for (_, before), (label, t) in zip(self.marks, self.marks[1:], strict=False)
        ]
        total = self.marks[-1][1] - self.marks[0][1]
        return f"start-up {total:.2f} s: " + ", ".join(steps)


def udp_only_transport(env=os.environ) -> None:
    """Receive over UDP, not shared memory (see the module's docstring); before rclpy.init."""
    env.setdefault("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4")


class CollectorRuntime:
    def __init__(
        self,
        *,
        vehicle: str,
        params_file: Path | None,
        name: str | None,
        spool: Path | None,
        start_logging: bool,
    ):
        self.host = socket.gethostname()
        self.vehicle_key = vehicle
        self.params_file = params_file
        self.name = name
        self.spool_path = spool
        self.start_logging = start_logging
        self.events: queue.Queue = queue.Queue()
        self.status = Status()
        self.collector = None
        # Records written since start; the heartbeat reports it for monitoring.
        self.stored = 0
        self._said_no_leg = None
        self._db_down_since = None
        self._last_mode_logged = None
        self.renew = threading.Event()
        self.startup = StartupTimes()
        self.startup.mark("Python, Django and the command loaded")

    # --- setup --------------------------------------------------------------------------

    def run(self, ros_args: list[str]) -> int:
        udp_only_transport()
        rclpy.init(args=["ftt_collect", "--ros-args", *ros_args])
        self.startup.mark("rclpy.init")
        try:
            code = self._run()
        finally:
            rclpy.try_shutdown()
        if self.renew.is_set():
            log.warning(gettext("renewing the collector: starting again in place"))
            os.environ[RENEWED_ENV] = str(time.time())
            os.execv(sys.executable, sys.orig_argv)
        return code

    def _deaf(self) -> None:
        """The node's deaf watch gave up on re-created subscriptions."""
        renewed = float(os.environ.get(RENEWED_ENV) or 0.0)
        if time.time() - renewed < RENEW_AT_MOST_EVERY_S:
            log.warning(gettext("renewed %.0f s ago already: not again yet"), time.time() - renewed)
            return
        self.renew.set()

    def _run(self) -> int:
        db = connections["default"]
        if db.vendor == "postgresql":
            # An unreachable server must fail fast, not hang the writer; keepalives
            # notice a connection that died with the robot's Wi-Fi within a minute
            # instead of the kernel's two hours.
            options = db.settings_dict.setdefault("OPTIONS", {})
            # One thread writes, so a pool (the web server's) gains nothing and
            # its reconnection backs off, doubling up to minutes, while the writer
            # waits up to the pool's timeout per attempt, so the collector would
            # come back long after the database. A plain connection, kept open
            # and checked, is tried again every RECONNECT.
            if options.pop("pool", None) is not None:
                db.settings_dict["CONN_MAX_AGE"] = None
                db.settings_dict["CONN_HEALTH_CHECKS"] = True
            for name, value in (
                ("connect_timeout", 3),
                ("keepalives", 1),
                ("keepalives_idle", 20),
                ("keepalives_interval", 5),
                ("keepalives_count", 4),
            ):
                options.setdefault(name, value)
        self.node = CollectorNode(
            self.events.put,
            params_file=self.params_file,
            status=self.status,
            on_logging=self._persist_logging,
            on_deaf=self._deaf,
            on_first_message=lambda: self.startup.mark("first message received"),
        )
        self.startup.mark("node, subscriptions and services")
        if self.vehicle_key:
            self.node.set_parameters([Parameter("vehicle", value=self.vehicle_key)])
        self.vehicle_key = self.node.get_parameter("vehicle").value
        self.name = self.name or f"{self.host}/{self.vehicle_key or self.node.get_name()}"
        self.spool = Spool(self.spool_path or default_spool(self.name))
        self.event_writer = EventWriter(self._leg)
        self.node.blackbox.directory = self.spool.path.with_suffix(".snapshots")
        self.disk = DiskGuard(self.spool.path)
        self.disk.snapshots = self.node.blackbox.directory
        self.node.disk = self.node.blackbox.guard = self.disk
        self.node.configure_disk()
        self.disk.make_reserve()
        self.spooler = Spooler(self.events, self.spool, self.disk, lambda: self.status.database_ok)
        self.order = ReplayOrder(self.spool, WRITE_BATCH, held=self.spooler.held)
        pending = len(self.spool)
        log.info(
            gettext("collector %s for vehicle '%s'; spool %s (%d records pending)"),
            self.name,
            self.vehicle_key,
            self.spool.path,
            pending,
        )
        if self.start_logging or self.spool.get_state("logging") == "1":
            self.node.set_logging(True)
        self.spooler.start()
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.ros_thread = threading.Thread(target=self._spin, name="ftt-ros", daemon=True)
        self.ros_thread.start()
        try:
            self._write_loop()
        except KeyboardInterrupt:
            pass  # rclpy's SIGINT handler chains to Python's: same as SIGTERM
        finally:
            self._shutdown()
        return 0

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except (ExternalShutdownException, KeyboardInterrupt):
            pass
        except Exception:
            log.exception("the ROS executor stopped")

    def _persist_logging(self, on: bool) -> None:
        try:
            self.spool.set_state("logging", "1" if on else "0")
        except SpoolFull:
            # Logging goes on; only a restart on this full disk would not resume it.
            line = (
                gettext("the robot disk is full: logging on is not kept for a restart")
                if on
                else gettext("the robot disk is full: logging off is not kept for a restart")
            )
            log.warning("%s", line)

    # --- database side ------------------------------------------------------------------

    def _vehicle(self):
        # Read on every lookup: an engineer may point a running collector at
        # another vehicle with `ros2 param set` or from the GUI.
        key = self.node.get_parameter("vehicle").value
        if key != self.vehicle_key:
            log.info(gettext("vehicle changed from '%s' to '%s'"), self.vehicle_key, key)
            self.vehicle_key = key
        return Vehicle.objects.filter(key=key).first() if key else None

    def _leg(self):
        vehicle = self._vehicle()
        return open_leg_for_vehicle(vehicle) if vehicle is not None else None

    def _write_loop(self) -> None:
        next_beat = next_commands = next_sync = next_prune = 0.0
        retry_at = 0.0
        while self.ros_thread.is_alive() and not self.renew.is_set():
            t = time.monotonic()
            if t < retry_at:
                time.sleep(0.1)
                continue
            try:
                if self.spooler.urgent.is_set():
                    self._write_change()
                if t >= next_beat:
                    self._heartbeat()
                    next_beat = t + HEARTBEAT
                if t >= next_commands:
                    self._commands()
                    next_commands = t + COMMAND_POLL
                if t >= next_prune:
                    feed.prune()
                    next_prune = t + 60
                if self._write_batch():
                    if not self.order.replaying:
                        self.spooler.urgent.wait(PACE)
                    continue
                if t >= next_sync:
                    self.event_writer.sync()
                    self._say_leg()
                    next_sync = t + SYNC
                self.spooler.spooled.wait(0.05)
                self.spooler.spooled.clear()
            except (DatabaseUnavailable, OperationalError, InterfaceError) as exc:
                self._database_down(exc)
                retry_at = time.monotonic() + RECONNECT
            except SpoolFull as exc:
                # Stored but not yet removed from the spool: tried again (as nothing
                # new: uids) once the disk has room; the disk guard says so once.
                self.disk.failed(exc)
                retry_at = time.monotonic() + RETRY

    def _write_change(self) -> None:
        """Store the segment change just spooled (with the positions before it)
        ahead of the heartbeat and the command poll, whose round trips a switch
        on the fleet view would otherwise wait for (docs/collector.md, the fleet
        benchmark). A few slices at most, so that a backlog never starves the
        heartbeat."""
        self.spooler.urgent.clear()
        for _ in range(URGENT_SLICES):
            if not self._write_batch() or self.order.stored_change:
                return

    def _write_batch(self) -> bool:
        taken = self.order.write_next(self.event_writer)
        if not taken:
            self.status.pending = 0
            return False
        self.stored += taken
        self.status.pending = self._pending()
        if not self.startup.reported and self.startup.has("first message received"):
            self.startup.mark("first record stored after it")
            self.startup.reported = True
            log.info("%s", self.startup.line())
        self._database_up()
        self._say_leg()
        return True

    def _pending(self) -> int:
        """Records not yet in the database: spooled, or held in memory (disk full)."""
        return len(self.spool) + len(self.spooler.held)

    def _say_leg(self) -> None:
        leg = self.event_writer.leg
        self.status.leg = f"{leg} of {leg.shift}" if leg is not None else None
        key = leg.pk if leg is not None else None
        if key == self._said_no_leg:
            return
        self._said_no_leg = key
        if leg is None:
            log.warning(
                gettext(
                    "no open leg for vehicle '%s': nothing is stored until one is opened "
                    "(still running)"
                ),
                self.vehicle_key,
            )

    def _database_down(self, exc) -> None:
        self.status.database_ok = False
        self.status.pending = self._pending()
        if self._db_down_since is None:
            self._db_down_since = timezone.now()
            log.warning(
                gettext("database unreachable (%s); spooling to %s"),
                str(exc).strip(),
                self.spool.path,
            )
        for conn in connections.all():
            try:
                conn.close()
            except Exception:
                pass

    def _database_up(self) -> None:
        if self._db_down_since is not None:
            log.warning(
                gettext("database back after %.0f s; replaying %d spooled records"),
                (timezone.now() - self._db_down_since).total_seconds(),
                len(self.spool),
            )
            self._db_down_since = None
        self.status.database_ok = True

    def _heartbeat(self) -> None:
        close_old_connections()
        leg = self.event_writer.leg
        fields = {
            "vehicle": self._vehicle(),
            "host": self.host,
            "pid": os.getpid(),
            "logging": self.node.pipeline.logging,
            "leg": leg,
            "state": self.status.describe(),
            "pending": self._pending(),
            "stored": self.stored,
            "parameters": self.node.current_parameters(),
            "topics": list(self.node.topics),
            "inputs": {k: dict(v) for k, v in self.node.inputs.items()},
            "hearing": self.node.hearing,
            "disk": self.disk.describe()[:300],
            "stopped": None,
        }
        if self.collector is None:
            fields["started"] = timezone.now()
        self.collector = link.heartbeat(self.name, **fields)
        self._database_up()

    def _commands(self) -> None:
        if self.collector is None:
            return
        for command in link.take_commands(self.collector):
            ok, message = self._execute(command)
            link.finish_command(
                command,
                ok,
                message,
                {
                    "parameters": self.node.current_parameters(),
                    "logging": self.node.pipeline.logging,
                },
            )
            self._heartbeat()

    def _execute(self, command) -> tuple[bool, str]:
        kind, node = command.kind, self.node
        calls = {
            CollectorCommand.Kind.START_LOGGING: (node.set_logging, True),
            CollectorCommand.Kind.STOP_LOGGING: (node.set_logging, False),
            CollectorCommand.Kind.SAVE_PARAMETERS: (node.save_parameters,),
            CollectorCommand.Kind.SNAPSHOT: (node.snapshot_now,),
            CollectorCommand.Kind.SET_PARAMETERS: (
                node.set_parameter_values,
                (command.arguments or {}).get("parameters") or {},
            ),
        }
        if kind not in calls:
            return False, gettext("Unknown command '%(kind)s'.") % {"kind": kind}
        fn, *args = calls[kind]
        try:
            return node.submit(fn, *args).result(timeout=5)
        except Exception as exc:
            return False, gettext("Failed: %(exc)s") % {"exc": exc}

    # --- exit ---------------------------------------------------------------------------

    def _shutdown(self) -> None:
        log.info(gettext("stopping: spooling what is still in memory"))
        self.executor.shutdown(timeout_sec=2)
        # The ROS thread is done with the pipeline: what waits for the first mode
        # is queued now, before the spooler drains the queue.
        self.node.pipeline.release_held()
        # Windows still open are written with what they have, unless the disk is
        # full or the writer is stuck: neither holds the exit.
        within = 0.0 if self.disk.level == FULL else EXIT_SNAPSHOT_SECONDS
        self.node.blackbox.close(within=within)
        self.spooler.stop.set()
        self.spooler.join(10)
        deadline = time.monotonic() + EXIT_FLUSH_SECONDS
        try:
            while time.monotonic() < deadline and self._write_batch():
                pass
            if self.collector is not None:
                self._heartbeat()  # the final counts
                link.mark_stopped(self.collector)
        except Exception as exc:
            log.warning(gettext("database not reachable at exit (%s)"), exc)
        held = list(self.spooler.held.events)
        if held:
            try:
                self.spool.append(held)
            except SpoolFull:
                log.error(
                    gettext(
                        "%d records held in memory are lost: the robot disk is full and the "
                        "database unreachable"
                    ),
                    len(held),
                )
        left = len(self.spool)
        if left:
            log.warning(gettext("%d records stay in %s for the next start"), left, self.spool.path)
        else:
            log.info(gettext("everything written"))
        self.spool.close()
        try:
            self.node.destroy_node()
        except Exception:
            pass
