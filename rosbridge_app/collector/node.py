"""The ROS side of ftt_collect: subscriptions, services and parameters.

Runs in one SingleThreadedExecutor thread.  Callbacks only convert and decide
(:class:`Pipeline`) and hand events to a thread-safe sink; nothing here waits
for the database.  Every callback catches its own exceptions: an exception
that escapes a callback would end ``spin()`` and with it the collector.
"""

import concurrent.futures
import copy
import functools
import logging
import queue
import threading
import time
from datetime import UTC, datetime
from pathlib import Path

from django.utils.translation import gettext, gettext_noop
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSPolicyKind, ReliabilityPolicy
from std_srvs.srv import SetBool, Trigger

from common.numbers import short
from rosbridge_app.collector import events as ev
from rosbridge_app.collector import params as P
from rosbridge_app.collector.answers import logging_answer
from rosbridge_app.collector.blackbox import Blackbox, snapshot_topics
from rosbridge_app.collector.conversions import stamp_ns
from rosbridge_app.collector.deaf_watch import RENEW, RESUBSCRIBE, STREAMS, DeafWatch
from rosbridge_app.collector.inputs import (
    drained_subscription,
    is_mode_input,
    qos,
    volatile_map_inputs,
    wanted_inputs,
)
from rosbridge_app.collector.losses import LossCounter
from rosbridge_app.collector.message_fields import message_class
from rosbridge_app.collector.mode_timing import sent_at
from rosbridge_app.collector.modes import ITO
from rosbridge_app.collector.pipeline import SECOND_COPY, Pipeline
from rosbridge_app.collector.status import Status

log = logging.getLogger("ftt.collector")


# Stamped streams whose lost messages are estimated (see losses.py).
LOSS_INPUTS = ("gps_fix", "local_pose")
LOSS_LOG_PERIOD = 10.0


def now() -> datetime:
    return datetime.now(UTC)


def _ignore(event) -> None:
    pass


class CollectorNode(Node):
    def __init__(
        self,
        sink,
        *,
        params_file: Path | None,
        status: Status | None = None,
        on_logging=None,
        on_deaf=None,
        on_first_message=None,
        overrides: dict | None = None,
    ):
        super().__init__(P.NODE_NAME)
        self.params_file = Path(params_file) if params_file else None
        self.status = status or Status()
        self.on_logging = on_logging or (lambda logging_on: None)
        # Called (executor thread) when re-created subscriptions did not help either.
        self.on_deaf = on_deaf or (lambda: None)
        self.on_first_message = on_first_message
        self._deaf_watch = DeafWatch(time.monotonic())
        self.inputs: dict[str, dict] = {}
        self.topics: list = []
        self._errors: dict[str, float] = {}
        self._ftt_subs: dict[str, object] = {}
        self._losses: dict[str, LossCounter] = {}
        self._losses_logged = 0.0
        self._ftt_services: dict[str, object] = {}
        self._calls: queue.Queue = queue.Queue()
        self._lock = threading.Lock()
        overrides = {
            **(P.written_documents(self.params_file) if self.params_file else {}),
            **(overrides or {}),
        }
        for name, spec in P.SPECS.items():
            descriptor = ParameterDescriptor(description=spec.description, dynamic_typing=True)
            value = self.declare_parameter(
                name, overrides.get(name, spec.default), descriptor
            ).value
            try:
                P.check(name, value)
            except P.InvalidParameter as exc:
                log.warning(gettext("%s; using the default %r"), exc, spec.default)
                self.set_parameters([Parameter(name, value=spec.default)])
        self.blackbox = Blackbox(sink, self.current_parameters())
        self.disk = None  # the runtime's DiskGuard, once it knows where the spool is
        self._snapshot_subs: dict[str, object] = {}
        self._master: str | None = None
        self.pipeline = Pipeline(self._watch_modes(sink), self.current_parameters())
        self.pipeline.mode_publisher = self._mode_publisher
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._parameters_changed)
        self._make_services()
        self._subscribe()
        self._guard = self.create_guard_condition(self._run_calls)
        self.create_timer(1.0, self._safe("tick", self._tick))
        self._tick()

    # --- parameters ---------------------------------------------------------------------

    def configure_disk(self) -> None:
        p = self.current_parameters()
        self.disk.configure(p["spool.disk_budget_mb"], p["spool.disk_headroom_mb"])

    def current_parameters(self) -> dict:
        return {name: self.get_parameter(name).value for name in P.SPECS}

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        try:
            for p in parameters:
                P.check(p.name, p.value)
        except P.InvalidParameter as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        except Exception as exc:  # an odd value must not take the executor down
            return SetParametersResult(successful=False, reason=f"invalid value: {exc}")
        return SetParametersResult(successful=True)

    def _parameters_changed(self, parameters: list[Parameter]) -> None:
        try:
            changed = {p.name: p.value for p in parameters if p.name in P.SPECS}
            self.pipeline.update_params(changed)
            if any(n.startswith("snapshot.") for n in changed):
                self.blackbox.configure(self.current_parameters())
            if self.disk is not None and any(n.startswith("spool.") for n in changed):
                self.configure_disk()
            if any(n.endswith("_service") for n in changed):
                self._make_services()
            if any(
                n.startswith("topics.")
                or n
                in (
                    "params.robot_mode_type",
                    "params.mode_sources",
                    "params.reason_rules",
                    "params.use_tf",
                    "params.sensor_reliable",
                )
                for n in changed
            ):
                self._subscribe()
            log.info(gettext("parameters changed: %s"), changed)
        except Exception:
            log.exception("applying parameter changes failed")

    def save_parameters(self) -> tuple[bool, str]:
        if self.params_file is None:
            return False, gettext("No parameters file: start ftt_collect with --params-file.")
        try:
            P.write_file(self.params_file, self.current_parameters())
        except Exception as exc:
            return False, gettext("Could not write %(file)s: %(exc)s") % {
                "file": self.params_file,
                "exc": exc,
            }
        return True, gettext("FTT parameters saved to %(file)s") % {"file": self.params_file}

    # --- services -----------------------------------------------------------------------

    def _make_services(self) -> None:
        for srv in self._ftt_services.values():
            self.destroy_service(srv)
        get = self.get_parameter
        self._ftt_services = {
            "set": self.create_service(
                SetBool, get("set_ftt_logging_service").value, self._srv_set_logging
            ),
            "get": self.create_service(
                Trigger, get("get_ftt_logging_service").value, self._srv_get_logging
            ),
            "save": self.create_service(
                Trigger, get("save_ftt_params_service").value, self._srv_save
            ),
            "snapshot": self.create_service(
                Trigger, get("snapshot_ftt_service").value, self._srv_snapshot
            ),
        }

    def set_logging(self, on: bool) -> tuple[bool, str]:
        if on == self.pipeline.logging:
            return True, logging_answer(on, "already", status=self.status.describe())
        try:
            self.on_logging(on)  # persists the state first: a restart resumes it
        except Exception as exc:
            return False, logging_answer(on, "failed", exc=exc)
        if on:
            self.pipeline.start_logging(now())
            return True, logging_answer(on, "done", status=self.status.describe())
        self.pipeline.stop_logging(now())
        return True, logging_answer(on, "done" if self.status.database_ok else "spooled")

    def _srv_set_logging(self, request, response):
        try:
            response.success, response.message = self.set_logging(bool(request.data))
        except Exception as exc:
            log.exception("set_ftt_logging failed")
            response.success = False
            response.message = gettext("Internal error: %(exc)s") % {"exc": exc}
        return response

    def _srv_get_logging(self, request, response):
        response.success = self.pipeline.logging
        try:
            line = (
                gettext("logging; %(status)s")
                if self.pipeline.logging
                else gettext("not logging; %(status)s")
            )
            response.message = line % {"status": self.status.describe()}
        except Exception as exc:
            response.message = gettext("status unknown: %(exc)s") % {"exc": exc}
        return response

    def _srv_save(self, request, response):
        response.success, response.message = self.save_parameters()
        return response

    def _srv_snapshot(self, request, response):
        response.success, response.message = self.snapshot_now()
        return response

    # --- black box ----------------------------------------------------------------------

    def _watch_modes(self, sink):
        def put(event):
            sink(event)
            if event.kind == ev.MODE:
                self._master = str(event.uid)
                if event.data["mode"] == ITO:
                    self.blackbox.trigger(event.at, self._master, gettext_noop("switch to ITO"))
            elif event.kind == ev.STOP:
                self._master = None

        return put

    def snapshot_now(self) -> tuple[bool, str]:
        uid = self.blackbox.trigger(now(), self._master, gettext_noop("on request"))
        if uid is None:
            return False, gettext("Snapshots are off (snapshot.enabled).")
        return True, gettext(
            "Snapshot %(uid)s of %(before)s s before and %(after)s s after now; stored when "
            "the window has passed."
        ) % {
            "uid": uid,
            "before": short(self.blackbox.before),
            "after": short(self.blackbox.after),
        }

    def _subscribe_snapshots(self) -> None:
        graph = {t["name"]: t["types"] for t in self.topics}
        # One process cannot subscribe to a topic with two types: on the
        # collector's own topics the black box takes the collector's type.
        graph.update({info["topic"]: [info["type"]] for info in self.inputs.values()})
        wanted = {}
        if self.blackbox.enabled:
            wanted = snapshot_topics(self.current_parameters(), graph, self.resolve_topic_name)
        gone = [t for t in self._snapshot_subs if self.blackbox.types.get(t) != wanted.get(t)]
        for topic in gone:
            self.destroy_subscription(self._snapshot_subs.pop(topic))
            self.blackbox.types.pop(topic, None)
        static = self.resolve_topic_name(self.get_parameter("topics.tf_static").value or "/")
        for topic, typename in wanted.items():
            if topic in self._snapshot_subs:
                continue
            latched = topic == static
            try:
                self._snapshot_subs[topic] = drained_subscription(
                    self,
                    message_class(typename),
                    topic,
                    self._safe("snapshot", functools.partial(self.blackbox.receive, topic)),
                    qos(100, latched, latched=latched),
                    raw=True,
                )
            except Exception as exc:
                log.error(
                    gettext("cannot subscribe to %s (%s) for snapshots: %s"), topic, typename, exc
                )
                continue
            self.blackbox.types[topic] = typename
            if latched:
                self.blackbox.latched.add(topic)

    # --- subscriptions ------------------------------------------------------------------

    def _safe(self, name: str, fn):
        @functools.wraps(fn)
        def wrapper(*args):
            try:
                return fn(*args)
            except Exception as exc:
                # Log each kind of failure at most every 10 s: a bad publisher
                # must not flood the log either.
                last = self._errors.get(name, 0.0)
                if time.monotonic() - last > 10:
                    self._errors[name] = time.monotonic()
                    log.warning(gettext("%s: ignored a message that failed: %r"), name, exc)

        return wrapper

    def _input(self, name: str, handler):
        def receive(msg, info=None):
            at = now()
            if self.on_first_message is not None:
                first, self.on_first_message = self.on_first_message, None
                first()
            answer = None
            try:
                if info is None or not is_mode_input(name):
                    answer = handler(msg, at)
                else:
                    answer = handler(msg, at, sent_at(info))
            finally:
                # Counted even when the handler fails: the message did arrive.
                heard = self.inputs.get(name)
                if heard is not None and answer is not SECOND_COPY:
                    heard["count"] += 1
                    heard["last_received"] = at.isoformat()
                    if name in LOSS_INPUTS:
                        self._count_losses(name, msg, info, heard)

        return self._safe(name, receive)

    def _count_losses(self, name: str, msg, info, heard: dict) -> None:
        counter = self._losses.setdefault(name, LossCounter())
        stamp = getattr(getattr(msg, "header", None), "stamp", None)
        sequence = info.get("publication_sequence_number") if info else None
        counter.seen(stamp_ns(stamp) / 1e9 if stamp is not None else None, sequence)
        heard.update(counter.report())

    def _log_losses(self, t: float) -> None:
        """Say in the log, at most every LOSS_LOG_PERIOD, when an input lost
        messages (a warning) or its publisher sent fewer than its rate (news)."""
        if t - self._losses_logged < LOSS_LOG_PERIOD:
            return
        self._losses_logged = t
        for name, counter in self._losses.items():
            new = counter.dropped - counter.logged
            if new > 0:
                counter.logged = counter.dropped
                log.warning(
                    gettext("%s: %d messages dropped in %g s (%d so far)"),
                    name,
                    new,
                    LOSS_LOG_PERIOD,
                    counter.dropped,
                )
            gaps = counter.gaps - counter.logged_gaps
            if gaps > 0:
                counter.logged_gaps = counter.gaps
                log.info(
                    gettext(
                        "%s: publisher gaps: about %d messages not sent at its rate in %g s "
                        "(%d so far); nothing was lost"
                    ),
                    name,
                    gaps,
                    LOSS_LOG_PERIOD,
                    counter.gaps,
                )

    def _subscribe(self) -> None:
        for sub in [*self._ftt_subs.values(), *self._snapshot_subs.values()]:
            self.destroy_subscription(sub)
        self._ftt_subs = {}
        # Made again at the next tick, with the types subscribed here.
        self._snapshot_subs = {}
        self.blackbox.types.clear()
        get = lambda name: self.get_parameter(name).value  # noqa: E731
        wanted = wanted_inputs(get, self.pipeline)
        inputs = {}
        for name, msg_type, topic, qos_profile, handler in wanted:
            if not topic:
                continue
            mode = is_mode_input(name)
            subscribe = functools.partial(
                drained_subscription,
                self,
                msg_type,
                topic,
                self._input(name, handler),
                # Loss inputs read their publisher's sequence numbers (losses.py).
                with_info=mode or name in LOSS_INPUTS,
                ahead=None if mode else self._take_modes,
            )
            try:
                self._ftt_subs[name] = subscribe(
                    qos_profile,
                    event_callbacks=SubscriptionEventCallbacks(
                        incompatible_qos=functools.partial(self._incompatible, name, subscribe)
                    ),
                )
                if mode:
                    # A publisher that latches its mode gives it to a late collector.
                    self._ftt_subs[f"{name} (latched)"] = drained_subscription(
                        self,
                        msg_type,
                        topic,
                        self._input(name, handler),
                        qos(1, True, latched=True),
                        with_info=True,
                        # A volatile publisher is heard by the other subscription:
                        # rclpy's "no messages will be received" warning would mislead.
                        event_callbacks=SubscriptionEventCallbacks(incompatible_qos=_ignore),
                    )
            except Exception as exc:
                log.error(gettext("cannot subscribe to %s (%s): %s"), topic, name, exc)
                continue
            old = self.inputs.get(name, {})
            resolved = self.resolve_topic_name(topic)
            inputs[name] = {
                "topic": resolved,
                "type": f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}",
                "count": old.get("count", 0) if old.get("topic") == resolved else 0,
                "last_received": old.get("last_received"),
            }
            if old.get("topic") != resolved:
                self._losses.pop(name, None)
            elif name in LOSS_INPUTS:
                inputs[name].update(self._losses.get(name, LossCounter()).report())
        for name, msg_type, handler in volatile_map_inputs(self.pipeline):
            if name in self._ftt_subs:
                self._ftt_subs[f"{name} (volatile)"] = drained_subscription(
                    self, msg_type, get(f"topics.{name}"), self._input(name, handler), qos(1, True)
                )
        self.inputs = inputs

    def _incompatible(self, name: str, subscribe, event) -> None:
        """A publisher on input ``name`` offers a QoS its subscription cannot
        match.  A best-effort publisher (many drivers are) is then heard by a
        second, best-effort subscription (``subscribe(qos)`` makes it), except on
        a sensor input the operator asked to hear reliably
        (``params.sensor_reliable``); anything else is said in the GUI, the
        input names the policy."""
        info = self.inputs.get(name)
        twin = f"{name} (best effort)"
        policy = QoSPolicyKind(event.last_policy_kind)
        insisted = not is_mode_input(name) and self.get_parameter("params.sensor_reliable").value
        if policy == QoSPolicyKind.RELIABILITY and not insisted:
            if twin not in self._ftt_subs:
                profile = copy.copy(self._ftt_subs[name].qos_profile)
                profile.reliability = ReliabilityPolicy.BEST_EFFORT
                self._ftt_subs[twin] = subscribe(profile)
            text = gettext("a publisher offers best effort: heard best effort")
        else:
            text = gettext(
                "a publisher's QoS is incompatible (%(policy)s): nothing is heard from it"
            ) % {"policy": policy.name}
        if info is not None and info.get("qos") != text:
            info["qos"] = text
            log.warning("%s (%s): %s", name, info["topic"], text)

    def _mode_publisher(self) -> bool:
        """Whether a publisher of the mode is matched with a mode subscription:
        a silent one says its mode only on change (collector/unknown_mode.py).
        The graph knows a publisher before its messages can reach the
        collector, so it is asked of the subscriptions, not the graph."""
        return any(
            sub.get_publisher_count()
            for key, sub in list(self._ftt_subs.items())
            if is_mode_input(key.split(" (")[0])
        )

    def _take_modes(self) -> None:
        """Mode messages go ahead of the sensor backlog being drained."""
        for key, sub in list(self._ftt_subs.items()):
            if is_mode_input(key.split(" (")[0]):
                sub.take_waiting()

    def _tick(self) -> None:
        self.pipeline.tick(now())
        self.topics = [
            {"name": name, "types": types} for name, types in self.get_topic_names_and_types()
        ]
        self._subscribe_snapshots()
        self.blackbox.poll()
        self._watch_hearing(time.monotonic())
        self._log_losses(time.monotonic())

    # --- deaf watch -------------------------------------------------------------------

    @property
    def hearing(self) -> str:
        """Empty, or what the GUI shows while the collector hears nothing."""
        return self._deaf_watch.text

    def _watch_hearing(self, t: float) -> None:
        received = sum(info["count"] for info in self.inputs.values())
        timeout = self.get_parameter("params.deaf_timeout").value
        action = self._deaf_watch.check(
            t, received, timeout, self.pipeline.logging, self._published_streams
        )
        if action == RESUBSCRIBE:
            self._subscribe()
        elif action == RENEW:
            self.on_deaf()

    def _published_streams(self) -> list[str]:
        me = (self.get_name(), self.get_namespace())
        found = []
        for name in STREAMS:
            info = self.inputs.get(name)
            if info is None:
                continue
            publishers = self.get_publishers_info_by_topic(info["topic"])
            if any((p.node_name, p.node_namespace) != me for p in publishers):
                found.append(info["topic"])
        return found

    # --- calls from other threads -------------------------------------------------------

    def submit(self, fn, *args) -> concurrent.futures.Future:
        """Run ``fn(*args)`` in the executor thread (ROS objects are not thread-safe)."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        self._calls.put((future, fn, args))
        self._guard.trigger()
        return future

    def _run_calls(self) -> None:
        while True:
            try:
                future, fn, args = self._calls.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            try:
                future.set_result(fn(*args))
            except Exception as exc:
                future.set_exception(exc)

    def set_parameter_values(self, values: dict) -> tuple[bool, str]:
        unknown = sorted(set(values) - set(P.SPECS))
        if unknown:
            return False, gettext("Unknown parameters: %(names)s") % {"names": ", ".join(unknown)}
        results = self.set_parameters(
            [Parameter(name, value=value) for name, value in values.items()]
        )
        failed = [
            f"{n}: {r.reason}" for n, r in zip(values, results, strict=True) if not r.successful
        ]
        if failed:
            return False, "; ".join(failed)
        return True, gettext("Set %(names)s.") % {"names": ", ".join(sorted(values))}
