"""Events → rows, through the logbook's and telemetry's services only.

Used by the live collector (events from its spool) and by bag imports
(events straight from :class:`~rosbridge_app.collector.pipeline.Pipeline`).
The leg is asked for at write time: live, that is the open leg of the
vehicle's open shift, so closing a leg in the GUI and opening another is
followed without a restart (the current mode is re-reported into the new leg,
and a new shift gets the current map).

Every row gets the event's uid (or one derived from it), so applying the same
events again stores nothing twice.
"""

import copy
import logging
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from django.db import InterfaceError, OperationalError, transaction
from django.utils import timezone
from django.utils.translation import gettext

from common.errors import RuleViolation
from events.history import authored
from events.models import Leg, Segment
from events.selectors.logs import open_master
from events.services.segments import (
    GpsPosition,
    LocalPosition,
    close_open_master,
    report_mode,
)
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.events import Event
from telemetry.services.attachments import attach_image, attach_recording
from telemetry.services.map_images import MapPicture, store_maps
from telemetry.services.pose_writes import GpsFix, MapPose, store_local_poses, store_poses

log = logging.getLogger("ftt.collector")
_MAP_PER_SHIFT = uuid.UUID("0c6f3d2e-57a4-4c57-9d53-3a7e4c1f2b90")


@dataclass(frozen=True)
class GivenMaster:
    """Positions, frames and snapshots go to this master (uid; None: nowhere),
    not to the open one: a backlog replayed after live data (collector/replay.py)."""

    master: str | None


class DatabaseUnavailable(Exception):
    """Nothing of the batch was stored; try the same events again later."""


def _unavailable(exc: BaseException) -> bool:
    return isinstance(exc, OperationalError | InterfaceError)


class EventWriter:
    def __init__(self, leg_provider: Callable[[], Leg | None]):
        self.leg_provider = leg_provider
        self.state = {
            "leg_id": None,
            "shift_id": None,
            "logging": False,
            "mode": None,  # data of the last mode event while logging
            "map": None,  # the last map event (data + blob), for a new shift
            "map_shift_id": None,
        }
        self.leg: Leg | None = None
        self.given: GivenMaster | None = None
        self._maps: list[Event] = []  # maps of the current run, stored together
        self._left_open: list[str | None] | None = None  # see apply_changes
        self.skipped = 0  # events that could not be placed (no leg, no segment, bad data)

    # --- public -------------------------------------------------------------------------

    @authored("collector")
    def apply(self, events: list[Event], master: GivenMaster | None = None) -> None:
        """Store events in order.  Raises DatabaseUnavailable with nothing stored
        (and this object's state unchanged) when the database cannot be used."""
        if master is not None and any(e.kind in ev.SEGMENT_CHANGES for e in events):
            raise ValueError("a segment change cannot be stored on a given master")
        saved = copy.copy(self.state), self.leg, self.skipped
        self.given = master
        try:
            with transaction.atomic():
                rest = self._stops_first(events)
                self._sync()
                self._apply_all(rest)
        except Exception as exc:
            self.state, self.leg, self.skipped = saved
            if _unavailable(exc):
                raise DatabaseUnavailable(str(exc)) from exc
            log.warning(
                gettext("a batch of %d events failed (%s); storing them one by one"),
                len(events),
                exc,
            )
            if self._left_open is not None:
                self._left_open = []
            self._apply_one_by_one(events)
        finally:
            self.given = None

    @authored("collector")
    def open_master_uid(self) -> str | None:
        """The uid of the master open now (after following leg changes)."""
        with transaction.atomic():
            self._sync()
            return self._master_uid()

    def apply_changes(self, events: list[Event]) -> list[str | None]:
        """Apply segment changes (and nothing else) in order; for each, the uid of
        the master it left open (None: none)."""
        if any(e.kind not in ev.SEGMENT_CHANGES for e in events):
            raise ValueError("only segment changes")
        self._left_open = []
        try:
            self.apply(events)
            return self._left_open
        finally:
            self._left_open = None

    def _master_uid(self) -> str | None:
        master = self._master()
        return str(master.uid) if master is not None else None

    def _note_left_open(self) -> None:
        if self._left_open is not None:
            self._left_open.append(self._master_uid())

    @authored("collector")
    def sync(self) -> Leg | None:
        """Follow leg changes now (called periodically while no events arrive)."""
        saved = copy.copy(self.state), self.leg
        try:
            with transaction.atomic():
                self._sync()
        except Exception as exc:
            self.state, self.leg = saved
            if _unavailable(exc):
                raise DatabaseUnavailable(str(exc)) from exc
            raise
        return self.leg

    # --- internals ----------------------------------------------------------------------

    def _apply_one_by_one(self, events: list[Event]) -> None:
        for event in events:
            saved = copy.copy(self.state), self.leg, self.skipped
            try:
                with transaction.atomic():
                    self._apply_all([event])
            except Exception as exc:
                self.state, self.leg, self.skipped = saved
                if _unavailable(exc):
                    raise DatabaseUnavailable(str(exc)) from exc
                self.skipped += 1
                log.warning(gettext("dropped a %s event: %s"), event.kind, exc)
                if event.kind in ev.SEGMENT_CHANGES:
                    self._note_left_open()
                if event.kind == ev.MODE:
                    # The robot is in this mode even though its segment could not
                    # be stored; the next leg must start in it, not in the old one.
                    self.state["logging"] = True
                    self.state["mode"] = dict(event.data)

    def _stops_first(self, events: list[Event]) -> list[Event]:
        """Apply the batch's leading stops in the leg they were meant for.

        A stop was given while logging into the leg seen so far; if the operator
        opened the next leg before the stop was stored, following that leg first
        would start a segment in it only to close it again at once.
        """
        count = 0
        while count < len(events) and events[count].kind == ev.STOP:
            self._on_stop(events[count])
            self._note_left_open()
            count += 1
        return events[count:]

    def _sync(self) -> None:
        leg = self.leg_provider()
        leg_id = leg.pk if leg is not None else None
        self.leg = leg
        if leg_id == self.state["leg_id"]:
            return
        self.state["leg_id"] = leg_id
        if leg is None:
            return
        log.info(gettext("logging into %s of %s"), leg, leg.shift)
        mode = self.state["mode"]
        if self.state["logging"] and mode is not None:
            report_mode(leg, mode["mode"], at=timezone.now())
        if self.state["map"] is not None and self.state["map_shift_id"] != leg.shift_id:
            self._store_map(self.state["map"])

    def _master(self) -> Segment | None:
        if self.given is not None:
            uid = self.given.master
            return Segment.objects.filter(uid=uid).first() if uid is not None else None
        return open_master(self.leg) if self.leg is not None else None

    def _apply_all(self, events: list[Event]) -> None:
        # GPS fixes and local poses go to two tables and only a segment change
        # (mode, start, stop) moves them to another master, so everything
        # between two changes is stored with one bulk insert per table; maps,
        # camera frames and snapshots go elsewhere and do not end the run.
        # Flushed at every map, a replayed outage spool cost two inserts and
        # two master lookups per two seconds of the robot's driving.
        fixes: list[Event] = []
        locals_: list[Event] = []
        self._maps = []
        for event in events:
            if event.kind == ev.GPS_FIX:
                fixes.append(event)
            elif event.kind == ev.LOCAL_POSE:
                locals_.append(event)
            else:
                if event.kind in ev.SEGMENT_CHANGES:
                    self._store_positions(fixes, locals_)
                    self._store_maps()
                    fixes, locals_ = [], []
                getattr(self, f"_on_{event.kind}")(event)
                if event.kind in ev.SEGMENT_CHANGES:
                    self._note_left_open()
        self._store_positions(fixes, locals_)
        self._store_maps()

    def _on_start(self, event: Event) -> None:
        self.state["logging"] = True

    def _on_stop(self, event: Event) -> None:
        self.state["logging"] = False
        self.state["mode"] = None
        if self.leg is not None:
            close_open_master(self.leg, at=max(event.at, self.leg.start))

    def _on_mode(self, event: Event) -> None:
        self.state["logging"] = True
        self.state["mode"] = dict(event.data)
        if self.leg is None:
            self.skipped += 1
            return
        data = event.data
        gps = local = None
        try:
            if data.get("gps"):
                gps = GpsPosition(*data["gps"])
            if data.get("local"):
                local = LocalPosition(*data["local"])
        except RuleViolation as exc:
            log.warning(gettext("mode switch recorded without its bad start position: %s"), exc)
        at = event.at
        current = self._master()
        if current is not None and at < current.start:
            # The robot's switch cannot be older than the open segment (a clock
            # step on the collector machine); record it at the segment's start.
            at = current.start
        report_mode(
            self.leg,
            data["mode"],
            at=max(at, self.leg.start),
            robot_stamp=data.get("robot_stamp"),
            start_uncertainty=data.get("start_uncertainty"),
            gps=gps,
            local=local,
            uid=event.uid,
            suggested_reason=data.get("suggested_reason"),
        )

    def _store_positions(self, fixes: list[Event], locals_: list[Event]) -> None:
        if not fixes and not locals_:
            return
        master = self._master()
        if master is None:
            self.skipped += len(fixes) + len(locals_)
            return
        if self.leg is not None and master.leg_id == self.leg.pk:
            # The leg (with its shift) as read for this batch: the services and the
            # feed would fetch both again for each table.
            master.leg = self.leg
        if fixes:
            self._store_fixes(master, fixes)
        if locals_:
            self._store_locals(master, locals_)

    def _store_fixes(self, master: Segment, fixes: list[Event]) -> None:
        rows = [
            GpsFix(
                longitude=e.data["lon"],
                latitude=e.data["lat"],
                altitude=e.data.get("alt"),
                fix_status=e.data.get("status", 0),
                horizontal_accuracy=e.data.get("accuracy"),
                robot_stamp=e.data.get("robot_stamp") or e.at,
                uid=e.uid,
            )
            for e in fixes
        ]
        store_poses(master, rows)

    def _store_locals(self, master: Segment, poses: list[Event]) -> None:
        rows = [
            MapPose(
                x=e.data["x"],
                y=e.data["y"],
                frame=e.data["frame"],
                yaw=e.data.get("yaw"),
                robot_stamp=e.data.get("robot_stamp") or e.at,
                uid=e.uid,
            )
            for e in poses
        ]
        store_local_poses(master, rows)

    def _on_map(self, event: Event) -> None:
        self.state["map"] = event
        if self.leg is None:
            self.skipped += 1
            return
        self._maps.append(event)

    def _store_maps(self) -> None:
        maps, self._maps = self._maps, []
        if not maps:
            return
        shift = self.leg.shift
        store_maps(shift, [self._map_picture(event, shift) for event in maps])
        self.state["map_shift_id"] = shift.pk

    def _store_map(self, event: Event) -> None:
        self._maps.append(event)
        self._store_maps()

    @staticmethod
    def _map_picture(event: Event, shift) -> MapPicture:
        d = event.data
        return MapPicture(
            png=event.blob,
            frame=d["frame"],
            width=d["width"],
            height=d["height"],
            resolution=d["resolution"],
            origin_x=d["origin_x"],
            origin_y=d["origin_y"],
            origin_yaw=d.get("origin_yaw", 0.0),
            robot_stamp=d.get("robot_stamp"),
            checksum=d.get("checksum"),
            # One map event may be stored in several shifts: one uid per shift.
            uid=uuid.uuid5(_MAP_PER_SHIFT, f"{event.uid}/{shift.uid}"),
        )

    def _on_image(self, event: Event) -> None:
        master = Segment.objects.filter(uid=event.data["master"]).first()
        if master is None or not event.blob:
            # The switch it belonged to was not a new segment (same mode already
            # open, e.g. after a restart) or was never stored.
            self.skipped += 1
            return
        attach_image(
            master,
            content=event.blob,
            description=event.data.get("description", ""),
            robot_stamp=event.data.get("robot_stamp"),
            uid=event.uid,
        )

    def _on_recording(self, event: Event) -> None:
        d = event.data
        path = Path(d["path"])
        master = Segment.objects.filter(uid=d["master"]).first() if d.get("master") else None
        master = master or self._master()
        if master is None or not path.is_file():
            # No segment to hang it on, or the file was dropped for the disk budget.
            self.skipped += 1
            why = "its file is gone" if master else "no segment"
            log.warning(gettext("snapshot %s not stored: %s"), path.name, why)
            return
        attach_recording(
            master,
            path=path,
            start=datetime.fromisoformat(d["start"]),
            end=datetime.fromisoformat(d["end"]),
            topics=d["topics"],
            reason=d.get("reason", ""),
            uid=event.uid,
        )
        # The pending file goes only once the row holding its copy is committed.
        transaction.on_commit(lambda: path.unlink(missing_ok=True))


def write_events(leg: Leg, events: list[Event]) -> EventWriter:
    """Store events into a fixed leg (a bag import): prepares and applies them."""
    event_writer = EventWriter(lambda: leg)
    batch = []
    for event in events:
        try:
            batch.append(event.prepare())
        except Exception as exc:
            log.warning(gettext("dropped a %s event: %s"), event.kind, exc)
    event_writer.apply(batch)
    return event_writer
