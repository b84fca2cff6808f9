"""From robot messages to events: the collector's decisions, free of ROS.

The live node calls these methods from its subscriptions, a bag import calls
them for every message of a bag; both hand the resulting events to the same
:class:`~rosbridge_app.collector.event_writer.EventWriter`.  ``at`` is always the
wall-clock time of the message (receive time live, record time in a bag).

Rules implemented here:
* the first mode after logging starts opens a segment, later ones only when
  the mode changes; the last mode is kept while logging is off, so a
  publisher that only sends on change is not missed;
* positions before the first mode are held and join the first segment when
  that mode says what they were, else a segment of unknown mode
  (unknown_mode.py);
* a segment starts at the last known GPS and local positions when they are
  fresh, and the latest fix closes the old segment and opens the new one, so
  per-segment paths add up to the whole path;
* positions are thinned (see thinning.py); unusable fixes and missing TF
  produce nothing, never a made-up (0, 0);
* maps are stored when they changed, at most every ``send_map_period``;
* camera frames go to a ring buffer that is written to each new master and
  then emptied.
"""

import hashlib
import logging
import uuid
from collections import deque
from collections.abc import Callable
from datetime import datetime

from django.utils.translation import gettext

from rosbridge_app.collector import conversions as conv
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.mode_sources import Combiner, Switch
from rosbridge_app.collector.mode_sources import parse as parse_mode_sources
from rosbridge_app.collector.mode_timing import ModeClock, plausible, stamp_of
from rosbridge_app.collector.modes import ITO, UNKNOWN, mode_of
from rosbridge_app.collector.params import SPECS
from rosbridge_app.collector.reason_rules import ReasonWatcher
from rosbridge_app.collector.reason_rules import parse as parse_reason_rules
from rosbridge_app.collector.tf_buffer import TfBuffer, TfLookupError
from rosbridge_app.collector.thinning import Thinner
from rosbridge_app.collector.unknown_mode import FirstMode, ModeWait

log = logging.getLogger("ftt.collector")

# The reason a switch suggests is asked of the rules at the switch (the default).
ASK = object()

# Returned by a handler for a second copy of a message it has already had, so
# the node does not count that copy as received (see Node._input).
SECOND_COPY = object()


def _seconds(at: datetime) -> float:
    return at.timestamp()


def _measured(at: datetime, value: dict) -> float:
    """Thinning runs on the robot's clock when the message has one, so a bag
    replayed faster than real time is thinned like the live robot."""
    stamp = value.get("robot_stamp")
    return _seconds(stamp if stamp is not None else at)


def _robot_time(held: tuple[datetime, dict]) -> datetime:
    """A held position's time on the clock mode messages are placed by."""
    at, value = held
    stamp = value.get("robot_stamp")
    return stamp if plausible(stamp, at) else at


class Pipeline:
    def __init__(self, sink: Callable[[Event], None], params: dict | None = None):
        self.sink = sink
        # Whether a publisher of the mode is connected now: the live node says;
        # a recording cannot (unknown_mode.py).
        self.mode_publisher: Callable[[], bool] = lambda: False
        self.params = {name: spec.default for name, spec in SPECS.items()}
        self.gps_thinner = Thinner(geographic=True)
        self.said_unknown_status = False  # logged once per run
        self.mode_clock = ModeClock()
        self.local_thinner = Thinner()
        self.tf = TfBuffer()
        self.images: deque = deque(maxlen=1)
        self.mode_sources: Combiner | None = None
        self.waiting = ModeWait()
        self.reasons: ReasonWatcher | None = None
        self.update_params(params or {})
        self.logging = False
        self.last_mode: str | None = None  # from the robot, logging or not
        self.open_mode: str | None = None  # what we last reported while logging
        self.last_fix: tuple[datetime, dict] | None = None
        self.last_fix_recorded = False
        self.last_local: tuple[datetime, dict] | None = None
        self.last_image_at: float | None = None
        self.grid_msg = None
        self.grid_quick: tuple | None = None
        self.grid_checksum: str | None = None
        self.grid_geometry: dict | None = None
        self.map_jpeg: bytes | None = None
        self.map_pending = False
        self.stored_map_checksum: str | None = None
        self.last_map_at: float | None = None
        self.last_tf_sample: int | None = None

    # --- configuration ------------------------------------------------------------------

    def update_params(self, changes: dict) -> None:
        self.params.update(changes)
        p = self.params
        self.gps_thinner.min_distance = p["params.pose_min_distance"]
        self.gps_thinner.min_period = p["params.pose_min_period"]
        self.local_thinner.min_distance = p["params.local_min_distance"]
        self.local_thinner.min_period = p["params.local_min_period"]
        self.local_thinner.min_yaw = p["params.local_min_yaw"]
        size = max(0, int(p["params.image_buffer_size"]))
        if self.images.maxlen != size:
            self.images = deque(self.images, maxlen=size)
        if "params.mode_sources" in changes:
            # Checked where the value was set; here it is only read.
            config = parse_mode_sources(p.get("params.mode_sources", ""))
            self.mode_sources = Combiner(config) if config else None
        if "params.reason_rules" in changes:
            rules = parse_reason_rules(p.get("params.reason_rules", ""))
            self.reasons = ReasonWatcher(rules) if rules else None
        if any(k in changes for k in ("params.map_frame", "params.robot_frame", "params.use_tf")):
            self.last_local = None
            self.local_thinner.reset()

    # --- logging on/off -----------------------------------------------------------------

    def start_logging(self, at: datetime) -> None:
        if self.logging:
            return
        self.logging = True
        self.open_mode = None
        self.waiting.clear()
        self.gps_thinner.reset()
        self.local_thinner.reset()
        self.stored_map_checksum = None
        self.sink(Event(ev.START, at))
        if self.last_mode is not None:
            self._switch(self.last_mode, at)
        if self.grid_msg is not None:
            self.map_pending = True
            self._maybe_store_map(at, force=True)

    def stop_logging(self, at: datetime) -> None:
        if not self.logging:
            return
        self.release_held()
        self._close_track(at)
        self.logging = False
        self.open_mode = None
        self.sink(Event(ev.STOP, at))

    def release_held(self) -> None:
        """Positions still waiting for the first mode go into a segment of unknown
        mode: when logging stops, and when the collector stops while logging
        (a restart continues that segment, as any left open)."""
        if self.logging and self.open_mode is None and self.waiting:
            if self.waiting.first_mode is not None:
                self._settle_first_mode()
            else:
                self._switch(UNKNOWN, self.waiting.first_at(), held=self.waiting.take())

    # --- mode ---------------------------------------------------------------------------

    def on_mode(self, msg, at: datetime, sent: datetime | None = None):
        """``sent``: when the publisher sent it (DDS source timestamp), if known."""
        mode = mode_of(msg, self.params["params.robot_mode_type"])
        if mode is None:
            return None
        placed = self.mode_clock.place(mode, stamp_of(msg), sent, at)
        if placed is None:
            return SECOND_COPY
        start, robot_stamp, uncertainty = placed
        if mode != self.last_mode and log.isEnabledFor(logging.DEBUG):
            # benchmarks/fleet.py splits a switch's way to the screen with it.
            log.debug("mode %s start=%.6f received=%.6f", mode, start.timestamp(), at.timestamp())
        self.on_mode_value(
            mode, start, robot_stamp=robot_stamp, uncertainty=uncertainty, received=at
        )
        return None

    def on_mode_source(
        self, indices: tuple[int, ...], msg, at: datetime, sent: datetime | None = None
    ):
        """A message of the topic of mode sources ``indices`` (params.mode_sources,
        each reading its field), sent at ``sent`` (DDS source timestamp) if known."""
        offers = [self.mode_sources.offer(i, msg, at, sent) for i in indices]
        if all(switches is None for switches in offers):
            return SECOND_COPY
        # A reason rule on the same topic sees the message before the switch it causes.
        self.on_reason_signal(self.mode_sources.config.sources[indices[0]].topic, msg, at)
        switches = [switch for switches in offers if switches for switch in switches]
        if switches:
            self._apply(switches, at)
        elif self.mode_sources.mode is not None:
            self._heard_again(self.mode_sources.mode, at)
        return None

    def _apply(self, switches: list[Switch], received: datetime) -> None:
        for switch in switches:
            self.on_mode_value(
                switch.mode,
                switch.at,
                robot_stamp=switch.robot_stamp,
                uncertainty=switch.uncertainty,
                received=received,
            )

    def on_reason_signal(self, topic: str, msg, at: datetime) -> None:
        """A message on a topic of params.reason_rules."""
        if self.reasons is not None:
            self.reasons.offer(topic, msg, at)

    def on_mode_value(
        self,
        mode: str,
        at: datetime,
        *,
        robot_stamp=None,
        uncertainty: float | None = None,
        received: datetime | None = None,
    ) -> None:
        """The robot's mode is ``mode`` since ``at``; ``received``: when the
        message saying so came (``at`` if not given)."""
        self.last_mode = mode
        if not self.logging:
            return
        received = received or at
        waiting = self.waiting
        if self.open_mode is None and waiting:
            if waiting.first_mode is not None:
                if mode == waiting.first_mode.mode:
                    self._heard_again(mode, received)
                    return
                self._settle_first_mode()
            elif waiting.says_what_was_held(at, self._first_held_robot_time()):
                self._switch(mode, waiting.first_at(), held=waiting.take())
                return
            else:
                waiting.first_mode = FirstMode(
                    mode, at, received, robot_stamp, uncertainty, self._reason(mode, at)
                )
                return
        if mode != self.open_mode:
            self._switch(mode, at, robot_stamp, uncertainty)

    def _first_held_robot_time(self) -> datetime:
        firsts = [held[0] for held in (self.waiting.fixes, self.waiting.poses) if held]
        return min(_robot_time(first) for first in firsts)

    def _heard_again(self, mode: str, received: datetime) -> None:
        """The mode is still ``mode``: a repeat proves the first mode message periodic."""
        waiting = self.waiting
        pending = waiting.first_mode
        if self.open_mode is None and pending is not None and mode == pending.mode:
            if waiting.repeats(received):
                self._switch(mode, waiting.first_at(), held=waiting.take())
            else:
                self._settle_first_mode()

    def _settle_first_mode(self) -> None:
        """The first mode message was a switch: what was held before it has no known mode."""
        message, first = self.waiting.first_mode, self.waiting.first_at()
        fixes, poses = self.waiting.take()

        def split(held):
            before = [h for h in held if _robot_time(h) < message.at]
            # As at every switch, the last position before it starts the new track.
            return before, before[-1:] + held[len(before) :]

        (fixes_before, fixes_after), (poses_before, poses_after) = split(fixes), split(poses)
        self._switch(UNKNOWN, first, held=(fixes_before, poses_before))
        self._switch(
            message.mode,
            message.at,
            message.robot_stamp,
            message.uncertainty,
            held=(fixes_after, poses_after),
            reason=message.reason,
        )

    def _reason(self, mode: str, at: datetime) -> str | None:
        return self.reasons.reason_at(at) if self.reasons and mode == ITO else None

    def _fresh(self, sample, at: datetime):
        if sample is None:
            return None
        when, value = sample
        if abs(_seconds(at) - _seconds(when)) > self.params["params.position_max_age"]:
            return None
        return value

    def _switch(
        self, mode: str, at: datetime, robot_stamp=None, uncertainty=None, held=None, reason=ASK
    ) -> None:
        """``held``: (fixes, poses) held before the mode was known that belong
        to this segment."""
        if self.open_mode is not None:
            self._close_track(at)
        fixes, poses = held or ([], [])
        fix = fixes[0][1] if fixes else self._fresh(self.last_fix, at)
        local = poses[0][1] if poses else self._fresh(self.last_local, at)
        master = uuid.uuid4()
        self.sink(
            Event(
                ev.MODE,
                at,
                {
                    "mode": mode,
                    "robot_stamp": robot_stamp,
                    "start_uncertainty": uncertainty,
                    "gps": [fix["lon"], fix["lat"]] if fix else None,
                    "local": [local["x"], local["y"], local["frame"]] if local else None,
                    "suggested_reason": self._reason(mode, at) if reason is ASK else reason,
                },
                uid=master,
            )
        )
        self.open_mode = mode
        # The new segment's track starts where the robot is now.
        self.gps_thinner.reset()
        self.local_thinner.reset()
        for when, kept in fixes:
            self._record_fix(when, kept)
        if fix is not None and not fixes:
            self._record_fix(self.last_fix[0], fix)
        for when, kept in poses:
            self._record_local(when, kept)
        if local is not None and not poses:
            self._record_local(self.last_local[0], local)
        self._flush_images(master, at)

    def _close_track(self, at: datetime) -> None:
        """The latest fix ends the old segment's track if thinning skipped it."""
        if self.last_fix is not None and not self.last_fix_recorded:
            fix = self._fresh(self.last_fix, at)
            if fix is not None:
                self._record_fix(self.last_fix[0], fix)

    # --- positions ----------------------------------------------------------------------

    def on_fix(self, msg, at: datetime) -> None:
        fix = conv.navsat_fix(msg)
        if fix is None:
            return
        if int(msg.status.status) == conv.STATUS_UNKNOWN and not self.said_unknown_status:
            self.said_unknown_status = True
            log.warning(
                gettext(
                    "gps_fix: the GPS driver leaves NavSatStatus unset (STATUS_UNKNOWN); "
                    "its fixes are recorded with the status 'fix'"
                )
            )
        self.last_fix = (at, fix)
        self.last_fix_recorded = False
        if self.logging and self.open_mode is not None:
            if self.gps_thinner.offer(fix["lon"], fix["lat"], _measured(at, fix)):
                self._emit_fix(at, fix)
        elif self.logging:
            if self.gps_thinner.offer(fix["lon"], fix["lat"], _measured(at, fix)):
                self._hold(self.waiting.fixes, at, fix)
            self._end_wait(at)

    def _end_wait(self, at: datetime) -> None:
        """The mode stayed unknown too long: a segment of unknown mode takes the
        held positions; a first mode message that can no longer prove periodic is a switch."""
        if not (self.logging and self.open_mode is None and self.waiting):
            return
        waiting = self.waiting
        if waiting.first_mode is not None:
            if at >= waiting.undecided_until(self.params["params.unknown_mode_wait"]):
                self._settle_first_mode()
        elif waiting.is_over(at, self.params["params.unknown_mode_wait"]):
            self._switch(UNKNOWN, waiting.first_at(), held=waiting.take())

    def _hold(self, held, at: datetime, value: dict) -> None:
        if not self.waiting:
            self.waiting.listening = self.mode_publisher()
        held.append((at, value))

    def _record_fix(self, at: datetime, fix: dict) -> None:
        self.gps_thinner.keep(fix["lon"], fix["lat"], _measured(at, fix))
        self._emit_fix(at, fix)

    def _emit_fix(self, at: datetime, fix: dict) -> None:
        self.last_fix_recorded = True
        self.sink(Event(ev.GPS_FIX, at, dict(fix)))

    def on_tf(self, msg, at: datetime, static: bool = False) -> None:
        if not self.params["params.use_tf"]:
            return
        for t in msg.transforms:
            try:
                self.tf.set_transform(
                    t.header.frame_id,
                    t.child_frame_id,
                    conv.transform_of(t.transform, t.header.stamp),
                    static=static,
                )
            except ValueError as exc:
                log.debug("ignored transform %s→%s: %s", t.header.frame_id, t.child_frame_id, exc)
        self._sample_tf(at)

    def _sample_tf(self, at: datetime) -> None:
        frame = self.params["params.map_frame"].lstrip("/")
        try:
            tf = self.tf.lookup(frame, self.params["params.robot_frame"])
        except TfLookupError:
            return  # not connected (yet): no local position, never (0, 0)
        if tf.stamp_ns == self.last_tf_sample:
            return
        self.last_tf_sample = tf.stamp_ns
        stamp = None
        if tf.stamp_ns:
            stamp = conv.stamp_to_datetime(_Stamp(tf.stamp_ns))
        self.on_local_value(
            {
                "x": tf.translation[0],
                "y": tf.translation[1],
                "yaw": tf.yaw,
                "frame": frame,
                "robot_stamp": stamp,
            },
            at,
        )

    def on_pose(self, msg, at: datetime) -> None:
        if self.params["params.use_tf"]:
            return
        pose = conv.pose_stamped(msg)
        if pose is None:
            return
        if not pose["frame"]:
            pose["frame"] = self.params["params.map_frame"].lstrip("/")
        self.on_local_value(pose, at)

    def on_local_value(self, pose: dict, at: datetime) -> None:
        self.last_local = (at, pose)
        if self.logging and self.open_mode is not None:
            if self.local_thinner.offer(pose["x"], pose["y"], _measured(at, pose), pose["yaw"]):
                self.sink(Event(ev.LOCAL_POSE, at, dict(pose)))
        elif self.logging:
            if self.local_thinner.offer(pose["x"], pose["y"], _measured(at, pose), pose["yaw"]):
                self._hold(self.waiting.poses, at, pose)
            self._end_wait(at)

    def _record_local(self, at: datetime, pose: dict) -> None:
        self.local_thinner.keep(pose["x"], pose["y"], _measured(at, pose), pose["yaw"])
        self.sink(Event(ev.LOCAL_POSE, at, dict(pose)))

    # --- map ----------------------------------------------------------------------------

    def on_grid(self, msg, at: datetime) -> None:
        # A latched map reaches both map subscriptions at once: the same stamp
        # and size within two seconds is that copy, so skip hashing 4 MB again.
        info = msg.info
        quick = (
            msg.header.stamp.sec,
            msg.header.stamp.nanosec,
            info.width,
            info.height,
            len(msg.data),
        )
        last_key, last_at = self.grid_quick or (None, None)
        if quick[:2] != (0, 0) and quick == last_key and _seconds(at) - last_at < 2.0:
            return SECOND_COPY
        self.grid_quick = (quick, _seconds(at))
        if not conv.grid_is_usable(msg):
            log.warning(
                gettext("ignored an empty or inconsistent map (%dx%d, %d cells)"),
                msg.info.width,
                msg.info.height,
                len(msg.data),
            )
            return
        geometry = conv.grid_geometry(msg)
        checksum = conv.grid_checksum(msg, geometry)
        if checksum == self.grid_checksum:
            return
        self.grid_msg, self.grid_geometry, self.grid_checksum = msg, geometry, checksum
        self.map_jpeg = None
        self.map_pending = True
        self._maybe_store_map(at)

    def on_map_jpeg(self, msg, at: datetime) -> None:
        """A ready-made picture of the map; the geometry still comes from the grid."""
        try:
            data, _ = conv.compressed_image(msg)
        except conv.UnsupportedImage as exc:
            log.warning(gettext("ignored map image: %s"), exc)
            return
        if data == self.map_jpeg:
            return
        self.map_jpeg = data
        if self.grid_geometry is not None:
            self.map_pending = True
            self._maybe_store_map(at)

    def tick(self, at: datetime) -> None:
        """Called about once a second: stores a map held back by send_map_period
        and confirms mode source values that held for their hysteresis."""
        if self.mode_sources is not None:
            self._apply(self.mode_sources.tick(at), at)
        self._end_wait(at)
        if self.map_pending:
            self._maybe_store_map(at)

    def _maybe_store_map(self, at: datetime, force: bool = False) -> None:
        if not self.logging or self.grid_geometry is None:
            return
        now = _seconds(at)
        period = self.params["params.send_map_period"]
        if not force and self.last_map_at is not None and now - self.last_map_at < period:
            return
        self.map_pending = False
        self.last_map_at = now
        msg, geometry, jpeg = self.grid_msg, dict(self.grid_geometry), self.map_jpeg
        checksum = self.grid_checksum
        if jpeg is not None:
            checksum = hashlib.sha256(checksum.encode() + jpeg).hexdigest()
        if checksum == self.stored_map_checksum:
            return
        self.stored_map_checksum = checksum

        def render():
            png = conv.any_image_to_png(jpeg) if jpeg is not None else conv.grid_to_png(msg)
            return {}, png

        self.sink(Event(ev.MAP, at, {**geometry, "checksum": checksum}, render=render))

    # --- camera -------------------------------------------------------------------------

    def on_image(self, msg, at: datetime, compressed: bool = False) -> None:
        if self.images.maxlen == 0:
            return
        now = _seconds(at)
        if (
            self.last_image_at is not None
            and now - self.last_image_at < self.params["params.image_buffer_step"]
        ):
            return
        self.last_image_at = now
        self.images.append((at, msg, compressed))

    def _flush_images(self, master: uuid.UUID, at: datetime) -> None:
        frames, max_side = list(self.images), self.params["params.image_max_side"]
        self.images.clear()
        for when, msg, compressed in frames:
            age = (at - when).total_seconds()

            def render(msg=msg, compressed=compressed):
                if compressed:
                    data, suffix = conv.compressed_image(msg)
                else:
                    data, suffix = conv.image_to_jpeg(msg, max_side), "jpg"
                return {"suffix": suffix}, data

            self.sink(
                Event(
                    ev.IMAGE,
                    at,
                    {
                        "master": str(master),
                        "robot_stamp": conv.stamp_to_datetime(msg.header.stamp),
                        "description": f"Camera, {age:.1f} s before the mode switch",
                    },
                    render=render,
                )
            )


class _Stamp:
    def __init__(self, ns: int):
        self.sec, self.nanosec = divmod(ns, 1_000_000_000)
