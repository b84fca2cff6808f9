"""Importing a robot recording (ROS 1 bag, ROS 2 sqlite3/mcap) with the live collector's rules.

The collector's own code does the work: :func:`rosbridge_app.collector.bag.bag_events`
turns the bag into the events a collector logging during the recording would
have produced, and its :class:`~rosbridge_app.collector.event_writer.EventWriter`
stores them through the services.  What this module adds:

* stable uids: each event's uid is derived from the recording (first and last
  record time in nanoseconds, message count), the target leg and the event's
  position in the bag, so a second import of the same recording (even renamed
  or converted from ROS 1 to ROS 2) finds every row and adds nothing;
* a place to put it: an open leg given by the user, or a new test event,
  shift and leg for the vehicle spanning the recording (also with stable uids,
  so they too are found again), closed at the bag's end.
"""

import functools
import tempfile
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from django.db import transaction
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from events.models import Leg, Shift, TestEvent, Vehicle
from events.services import logs
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.bag import bag_events, open_bag
from rosbridge_app.collector.blackbox import snapshot_topics
from rosbridge_app.collector.event_writer import EventWriter
from rosbridge_app.collector.events import Event
from rosbridge_app.collector.mcap_files import MessageDefinitions, write_mcap
from rosbridge_app.collector.message_fields import installed_fields, recorded_fields
from rosbridge_app.collector.modes import ITO
from rosbridge_app.collector.params import SPECS, InvalidParameter, check
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording

NAMESPACE = uuid.UUID("b3f5a6f0-8e0c-4a51-9d8e-2c1a7d4e6b20")
BATCH = 500


class BagImportError(Exception):
    pass


@dataclass
class BagInfo:
    path: Path
    uid: uuid.UUID
    first: datetime
    last: datetime
    messages: int
    topics: dict[str, str]  # topic → message type, as recorded


@dataclass
class BagImportResult:
    leg: Leg
    events: int
    added: dict
    skipped: int


def bag_info(path) -> BagInfo:
    path = Path(path)
    try:
        with open_bag(path) as reader:
            start, end, count = reader.start_time, reader.end_time, reader.message_count
            topics = {c.topic: c.msgtype for c in reader.connections}
    except Exception as exc:  # rosbags raises its own reader errors
        raise BagImportError(
            _("Cannot read %(path)s: %(exc)s") % {"path": path, "exc": exc}
        ) from None
    if not count:
        raise BagImportError(_("%(path)s contains no messages.") % {"path": path})
    return BagInfo(
        path=path,
        uid=uuid.uuid5(NAMESPACE, f"{start}:{end}:{count}"),
        first=datetime.fromtimestamp(start / 1e9, tz=UTC),
        last=datetime.fromtimestamp(end / 1e9, tz=UTC),
        messages=count,
        topics=topics,
    )


def collector_params(overrides: dict, path: Path | None = None) -> dict:
    """The collector's defaults with the given ``topics.*``/``params.*`` changed;
    mode sources and reason rules are checked against the types recorded in
    the bag at ``path`` too (ROS 1 bags and MCAP carry their definitions)."""
    fields_of = installed_fields
    if path is not None:
        with open_bag(path) as reader:
            fields_of = recorded_fields(reader.typestore)
    params = {name: spec.default for name, spec in SPECS.items()}
    for name, value in overrides.items():
        if name not in SPECS:
            raise BagImportError(_("Unknown collector parameter '%(name)s'.") % {"name": name})
        try:
            params[name] = check(name, value, fields_of)
        except InvalidParameter as exc:
            raise BagImportError(str(exc)) from None
    return params


def stabilise(events, namespace: uuid.UUID) -> None:
    """Replace the events' random uids by ones that the same bag reproduces."""
    renamed = {}
    for index, event in enumerate(events):
        new = uuid.uuid5(namespace, f"{index}:{event.kind}:{event.at.isoformat()}")
        renamed[str(event.uid)] = str(new)
        event.uid = new
    for event in events:
        master = event.data.get("master")
        if master is not None:
            event.data["master"] = renamed.get(str(master), master)


def _target_leg(info: BagInfo, vehicle: Vehicle, leg: Leg | None, event: TestEvent | None):
    """The leg to log into and whether this import created (and must close) it."""
    if leg is not None:
        if leg.shift.vehicle_id != vehicle.pk:
            raise BagImportError(
                _("%(leg)s belongs to a shift of vehicle '%(owner)s', not '%(vehicle)s'.")
                % {
                    "leg": leg,
                    "owner": leg.shift.vehicle.key,
                    "vehicle": vehicle.key,
                }
            )
        if leg.end is not None:
            raise BagImportError(
                _("%(leg)s of %(shift)s is closed; give an open leg or none.")
                % {"leg": leg, "shift": leg.shift}
            )
        if leg.start > info.first:
            raise BagImportError(
                _(
                    "%(leg)s starts at %(start)s, after the recording (%(recording)s); omit "
                    "--leg to import into a new test event."
                )
                % {"leg": leg, "start": leg.start.isoformat(), "recording": info.first.isoformat()}
            )
        return leg, False
    shift_uid = uuid.uuid5(info.uid, f"shift:{vehicle.key}")
    known = Shift.objects.filter(uid=shift_uid).first()
    if known is None:
        other = Shift.objects.filter(vehicle=vehicle, end__isnull=True).first()
        if other is not None:
            # Starting a shift closes the vehicle's open one; a recording from
            # the past must not end today's logging.
            raise BagImportError(
                _(
                    "Vehicle '%(vehicle)s' has an open shift (%(other)s of "
                    "%(event)s); end it first or import into its leg with "
                    "--leg."
                )
                % {"vehicle": vehicle.key, "other": other, "event": other.test_event}
            )
    if event is None:
        event = logs.create_test_event(
            uid=uuid.uuid5(info.uid, f"test_event:{vehicle.key}"),
            at=info.first,
            note=f"Imported from {info.path.name}",
        )
    elif event.end is not None or event.start > info.first:
        raise BagImportError(
            _("Test event '%(event)s' must be open and start before the recording.")
            % {"event": event}
        )
    shift = logs.create_shift(test_event=event, vehicle=vehicle, uid=shift_uid, at=info.first)
    leg = logs.create_leg(
        shift=shift,
        uid=uuid.uuid5(info.uid, f"leg:{vehicle.key}"),
        at=info.first,
        recording=str(info.path.name),
    )
    return leg, True


def snapshot_events(info: BagInfo, settings: dict, events: list, directory: Path) -> list:
    """The black box's windows cut out of the recording: a ``recording`` event
    (and its MCAP file in ``directory``) for every switch to ITO in ``events``."""
    switches = [e for e in events if e.kind == ev.MODE and e.data["mode"] == ITO]
    if not switches:
        return []
    before, after = (int(settings[f"snapshot.{k}"] * 1e9) for k in ("before", "after"))
    out = []
    with open_bag(info.path) as reader:
        graph = {c.topic: [c.msgtype] for c in reader.connections}
        types = snapshot_topics(settings, graph, lambda n: n if n.startswith("/") else f"/{n}")
        connections = [c for c in reader.connections if c.topic in types]
        definitions = MessageDefinitions(reader.typestore)
        for switch in switches:
            at = int(switch.at.timestamp() * 1e9)
            messages = [
                (t, c.topic, raw if reader.is2 else _cdr(reader, raw, c.msgtype))
                for c, t, raw in reader.messages(
                    connections=connections, start=at - before, stop=at + after + 1
                )
            ]
            path = directory / f"snapshot-{switch.at:%Y%m%d-%H%M%S}-{switch.uid.hex[:8]}.mcap"
            data = {
                "master": str(switch.uid),
                "reason": gettext_noop("bag import"),
                "path": str(path),
                "start": datetime.fromtimestamp((at - before) / 1e9, UTC).isoformat(),
                "end": datetime.fromtimestamp((at + after) / 1e9, UTC).isoformat(),
                "topics": write_mcap(path, messages, types, definitions),
            }
            out.append(Event(ev.RECORDING, switch.at, data, uid=uuid.uuid5(switch.uid, "bb")))
    return out


def _cdr(reader, raw: bytes, msgtype: str) -> bytes:
    # Re-encoded with the reader's own types, which the file's schemas describe.
    store = reader.typestore
    return bytes(store.serialize_cdr(reader.deserialize(raw, msgtype), msgtype))


def _counts(snapshots: bool) -> dict:
    models = (Pose, LocalPose, MapImage, Image, *((Recording,) if snapshots else ()))
    return {m.__name__: m.objects.count() for m in models}


def _nothing_stored(info: BagInfo, settings: dict) -> str:
    recorded = ", ".join(f"{topic} ({kind})" for topic, kind in sorted(info.topics.items()))
    return _(
        "Nothing of %(path)s was stored: it holds no mode on the mode topic read (%(mode)s) "
        "and no GPS fix, transform or pose. It holds: %(recorded)s. Name the mode topic "
        "with --topic robot_mode=… (its type with --mode-type or params.mode_sources), "
        "or give the robot's --params-file."
    ) % {"path": info.path.name, "mode": settings["topics.robot_mode"], "recorded": recorded}


def import_bag(
    path,
    *,
    vehicle: Vehicle,
    leg: Leg | None = None,
    test_event: TestEvent | None = None,
    params: dict | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    snapshots: bool = False,
) -> BagImportResult:
    """``progress(phase, done, total)``: phase "reading" counts the bag's messages,
    "storing" the collector events made from them.  ``snapshots``: also cut the
    black box's window (``snapshot.*`` in ``params``) around every take-over."""
    info = bag_info(path)
    settings = collector_params(params or {}, info.path)
    reading = None if progress is None else functools.partial(progress, "reading")
    events = bag_events(info.path, settings, progress=reading)
    before = _counts(snapshots)
    scratch = tempfile.TemporaryDirectory(prefix="ftt-bag-snapshots-")
    with scratch, transaction.atomic():
        target, created = _target_leg(info, vehicle, leg, test_event)
        stabilise(events, uuid.uuid5(info.uid, str(target.uid)))
        if snapshots:
            events += snapshot_events(info, settings, events, Path(scratch.name))
        event_writer = EventWriter(lambda: target)
        unreadable = 0
        for start in range(0, len(events), BATCH):
            batch = []
            for event in events[start : start + BATCH]:
                try:
                    batch.append(event.prepare())
                except Exception:  # a picture that cannot be decoded, as when live
                    unreadable += 1
            event_writer.apply(batch)
            if progress is not None:
                progress("storing", min(start + BATCH, len(events)), len(events))
        if created and not target.segments.exists():
            # Undone with the transaction: an empty, closed test event would
            # take this recording's uids, and the corrected import would then
            # store nothing either.
            raise BagImportError(_nothing_stored(info, settings))
        if created:
            target.refresh_from_db()
            shift, event = target.shift, target.shift.test_event
            if event.end is None and test_event is None:
                logs.close_test_event(event, at=info.last)
            elif shift.end is None:
                logs.close_shift(shift, at=info.last)
    after = _counts(snapshots)
    return BagImportResult(
        leg=target,
        events=len(events),
        added={name: after[name] - before[name] for name in after},
        skipped=event_writer.skipped + unreadable,
    )
