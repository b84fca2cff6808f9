"""Bringing archived rows into this installation: all or nothing, and idempotent.

Rules (docs/data-exchange.md explains them for administrators):

* Log entries, notes and telemetry are matched by ``uid``.  A known uid is
  updated where the archive differs and its copy changed later than ours
  (``modified``; the later change wins, and a segment's annotation by its own
  stamp ``annotated``), otherwise left alone; an unknown one is
  added with the archive's uid, times and ordinal number.  Numbers are never
  changed: if the number is taken by another entry of the same parent the
  import is refused.
* An import never re-opens what is closed here, because an older archive of a
  still running shift must not undo the end someone recorded since.
* An open entry that would meet another open one (a second open shift of a
  vehicle, a second open leg of a shift, a second open master of a leg) is
  refused; close one of them and import again.
* Notes change only when the archive's copy was edited later than ours.
  Track points and maps never change once stored; of an image only the
  description can.
* Configuration rows are reused when they match: catalogues, vehicles and pose
  sources by key, performers by institution, personnel by name and institution
  (both ignoring case and surrounding blanks).  Otherwise they are added.
  Reused rows keep their local descriptions.

The historical rows are written directly (the services only open entries "now"),
inside one transaction, after ``full_clean`` and the checks above, which ask
the same rule functions as the services (:mod:`events.rules`, the map checks
of :func:`telemetry.services.map_images.check_map_placement`); the database
constraints stay the last guard.  Files written before a failure are removed.
What changed is announced in the change feed in the same transaction.
"""

import uuid
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from itertools import islice
from pathlib import PurePosixPath

from django.core.exceptions import ValidationError
from django.core.files.base import ContentFile
from django.db import DatabaseError, IntegrityError, transaction
from django.db.models import Q

from basemaps.models import BasemapLayer, EventBasemap
from basemaps.services import layers as basemap_layers
from events import feed, rules
from events.models import (
    ItoReason,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    SegmentType,
    Shift,
    TestEvent,
    Vehicle,
    Weather,
)
from exchange import records as rec
from exchange.archive import ArchiveError
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.pictures import MAP_FORMATS, PHOTO_FORMATS, checked_picture
from telemetry.services.map_images import check_map_placement
from telemetry.services.recording import GpsFix, MapPose

BATCH = 2000
# Every MCAP file starts with these bytes (the format's magic).
MCAP_MAGIC = b"\x89MCAP0\r\n"
OUTCOMES = ("added", "updated", "unchanged", "reused")
CATALOGUES = {"weather": Weather, "segment_types": SegmentType, "ito_reasons": ItoReason}


class ImportRefused(Exception):
    """The data cannot be imported as it is; nothing was changed."""


class MalformedRecord(ImportRefused):
    """A record or file has the wrong shape (a bad request, not a conflict with data here)."""


@dataclass
class Plan:
    dry_run: bool = False
    counts: dict = field(default_factory=lambda: defaultdict(Counter))

    def note(self, table: str, outcome: str, n: int = 1) -> None:
        if n:
            self.counts[table][outcome] += n

    def total(self, outcome: str) -> int:
        return sum(c[outcome] for c in self.counts.values())

    def changes(self) -> int:
        return self.total("added") + self.total("updated")

    def verdict(self) -> str:
        if self.dry_run:
            return f"Would change {self.changes()} row(s); dry run, nothing written."
        return f"Changed {self.changes()} row(s)."

    def lines(self) -> list[str]:
        head = f"{'':14}" + "".join(f"{o:>11}" for o in OUTCOMES)
        rows = [head]
        for table in rec.TABLES:
            if table in self.counts:
                c = self.counts[table]
                rows.append(f"{table:14}" + "".join(f"{c[o]:>11}" for o in OUTCOMES))
        return rows


def _clean(text) -> str:
    return (text or "").strip()


def _fold(text) -> str:
    # In Python, not SQL: SQLite's case folding stops at ASCII ("Müller").
    return " ".join((text or "").split()).casefold()


def _batches(iterable, size):
    iterator = iter(iterable)
    while batch := list(islice(iterator, size)):
        yield batch


class _Importer:
    def __init__(self, bundle, dry_run: bool):
        self.bundle = bundle
        self.dry_run = dry_run
        self.plan = Plan(dry_run=dry_run)
        self.written: list = []  # (storage, name) of files saved so far
        self.where = ""
        self.vehicles: dict[str, Vehicle] = {}
        self.pose_sources: dict[str, PoseSource] = {}
        self.performers: dict[str, Performer] = {}
        self.people: dict[str, Personnel] = {}
        self.events: dict[str, int] = {}
        self.shifts: dict[str, int] = {}
        self.legs: dict[str, int] = {}
        self.segments: dict[str, tuple[int, int | None, int]] = {}
        self.masters: dict[str, Segment] = {}
        # For the change feed: rows added or changed, and new track points per master.
        self.changed: list = []
        self.track_points: Counter = Counter()

    # --- reading -------------------------------------------------------------------------

    def records(self, table: str):
        for record in self.bundle.records(table):
            self.where = f"{table} record {record.get('uid') or record.get('key') or ''}".strip()
            for name in ("uid", "key"):
                if name in record and not isinstance(record[name], str):
                    raise MalformedRecord(f"{self.where}: its {name} must be a string.")
            yield record

    def refuse(self, message: str):
        raise ImportRefused(message)

    # --- configuration -------------------------------------------------------------------

    def catalogues(self):
        for table, model in CATALOGUES.items():
            known = set(model.objects.values_list("key", flat=True))
            names = {f.name for f in model._meta.concrete_fields}
            for record in self.records(table):
                if record["key"] in known:
                    self.plan.note(table, "reused")
                    continue
                row = model(**{k: v for k, v in record.items() if k in names})
                row.full_clean()
                row.save()
                known.add(row.key)
                self.plan.note(table, "added")

    def _reuse_or_add(self, table, existing, make):
        if existing is not None:
            self.plan.note(table, "reused")
            return existing
        row = make()
        row.full_clean()
        row.save()
        self.plan.note(table, "added")
        return row

    def configuration(self):
        for model, table, cache, extra in (
            (Vehicle, "vehicles", self.vehicles, ("institution", "configuration")),
            (PoseSource, "pose_sources", self.pose_sources, ()),
        ):
            for r in self.records(table):
                fields = ("key", "short_description", "long_description", *extra)
                cache[r["key"]] = self._reuse_or_add(
                    table,
                    model.objects.filter(key=r["key"]).first(),
                    lambda r=r, model=model, fields=fields: model(**{f: r[f] for f in fields}),
                )
        performers = {_fold(p.institution): p for p in Performer.objects.order_by("-pk")}
        for r in self.records("performers"):
            institution = _clean(r["institution"])
            row = self._reuse_or_add(
                "performers",
                performers.get(_fold(institution)),
                lambda institution=institution: Performer(institution=institution),
            )
            self.performers[r["institution"]] = performers[_fold(institution)] = row
        people = {
            (_fold(p.name), _fold(p.institution)): p for p in Personnel.objects.order_by("-pk")
        }
        for r in self.records("personnel"):
            name, institution = _clean(r["name"]), _clean(r["institution"])
            match = (_fold(name), _fold(institution))
            row = self._reuse_or_add(
                "personnel",
                people.get(match),
                lambda name=name, institution=institution: Personnel(
                    name=name, institution=institution
                ),
            )
            self.people[r["ref"]] = people[match] = row

    def _config(self, cache: dict, model, key, label: str):
        """A configuration row named by a record; looked up here if the archive lacks it."""
        if key is None:
            return None
        if key not in cache:
            if model is Performer:
                row = next(
                    (p for p in Performer.objects.all() if _fold(p.institution) == _fold(key)),
                    None,
                )
            else:
                row = model.objects.filter(key=key).first()
            if row is None:
                self.refuse(f"{self.where}: unknown {label} '{key}'.")
            cache[key] = row
        return cache[key]

    def _person(self, ref):
        if ref is None:
            return None
        if ref not in self.people:
            self.refuse(f"{self.where}: refers to person '{ref}' the archive does not list.")
        return self.people[ref].pk

    # --- log entries ---------------------------------------------------------------------

    def _parent(self, cache: dict, model, uid, label: str) -> int:
        if uid not in cache:
            pk = model.objects.filter(uid=uid).values_list("pk", flat=True).first()
            if pk is None:
                self.refuse(f"{self.where}: its {label} {uid} is neither in the archive nor here.")
            cache[uid] = pk
        return cache[uid]

    def save_entry(self, table, model, record, values, *, parent=None, clashes=(), annotation=None):
        """Add or update one log entry.

        ``clashes`` are (queryset, message) pairs that must be empty before a new
        entry may be added.  ``annotation`` holds a segment's reason fields: they
        follow their own stamp (``annotated``), so that an operator's annotation
        survives the robot closing the same segment later on the other side.
        """
        uid = uuid.UUID(record["uid"])
        # Archives written before rows carried change stamps have none: then the
        # archive's copy is taken, as it always was.
        modified = rec.time_in(record.get("modified"), "modified")
        annotated = rec.time_in(record.get("annotated"), "annotated")
        annotation = annotation or {}
        row = model.objects.filter(uid=uid).first()
        if row is None:
            for queryset, message in clashes:
                other = queryset.first()
                if other is not None:
                    self.refuse(f"{message} (here: uid {other.uid}; archive: uid {uid}).")
            row = model(uid=uid, **values, **annotation)
            if modified is not None:
                row.modified = modified
            if annotation:
                row.annotated = annotated
            row.full_clean(validate_unique=False, validate_constraints=False)
            row.save(keep_modified=modified is not None)
            self.plan.note(table, "added")
            self.changed.append(row)
            return row
        if parent and getattr(row, parent) != values[parent]:
            self.refuse(
                f"{self.where}: this entry hangs under a different parent here than in "
                f"the archive; the two installations disagree about uid {uid}."
            )
        values.pop("number", None)
        wanted = {}
        # A copy not newer than ours was made before our latest change: a stale
        # archive must not undo what was recorded later.
        if modified is None or modified > row.modified:
            if row.end is not None and values.get("end", row.end) is None:
                values["end"] = row.end  # never re-open; see the module docstring
            wanted |= values
        stamps = []
        if annotation and ("annotated" not in record or _later(annotated, row.annotated)):
            wanted |= annotation
            if row.annotated != annotated:
                row.annotated = annotated
                stamps.append("annotated")
        if _later(modified, row.modified):
            row.modified = modified
            stamps.append("modified")
        changed = [name for name, value in wanted.items() if getattr(row, name) != value]
        for name in changed:
            setattr(row, name, wanted[name])
        if changed:
            row.full_clean(validate_unique=False, validate_constraints=False)
        if changed or stamps:
            # Stamps move along also without a change of content (saved again there).
            row.save(update_fields=[*changed, *stamps], keep_modified=modified is not None)
        self.plan.note(table, "updated" if changed else "unchanged")
        if changed:
            self.changed.append(row)
        return row

    @staticmethod
    def _entry_values(record) -> dict:
        return {
            "start": rec.time_in(record["start"], "start"),
            "end": rec.time_in(record["end"], "end"),
            "note": record.get("note", ""),
        }

    @staticmethod
    def _closed_first(records) -> list:
        # Entries that end are applied before open ones, so that closing an old
        # shift makes room for the archive's newer open shift.
        return sorted(records, key=lambda r: (r.get("end") is None, r["start"]))

    def test_events(self):
        for r in self.records("test_events"):
            values = self._entry_values(r) | {
                "location": r["location"],
                "version": r["version"],
                "time_zone": r["time_zone"],
            }
            self.events[r["uid"]] = self.save_entry("test_events", TestEvent, r, values).pk

    def basemap_links(self):
        for r in self.records("basemaps"):
            event_id = self._parent(self.events, TestEvent, r["test_event"], "test event")
            layer = BasemapLayer.objects.filter(key=r["key"]).first()
            if layer is None and r.get("kind") == BasemapLayer.URL:
                layer = basemap_layers.register_url(
                    r["url"],
                    name=r["name"],
                    attribution=r.get("attribution", ""),
                    max_zoom=r.get("max_zoom", 19),
                    key=r["key"],
                )
            if layer is None:
                # The file is not here; a backup, not an archive, moves basemap files.
                self.plan.note("basemaps", "unchanged")
                continue
            current = EventBasemap.objects.filter(test_event_id=event_id).first()
            if current is not None and current.layer_id == layer.pk:
                self.plan.note("basemaps", "unchanged")
                continue
            basemap_layers.set_event_default(TestEvent(pk=event_id), layer)
            self.plan.note("basemaps", "added" if current is None else "updated")

    def shift_rows(self):
        for r in self._closed_first(self.records("shifts")):
            self.where = f"shifts record {r['uid']}"
            event_id = self._parent(self.events, TestEvent, r["test_event"], "test event")
            vehicle = self._config(self.vehicles, Vehicle, r["vehicle"], "vehicle")
            performer = self._config(self.performers, Performer, r["performer"], "performer")
            values = self._entry_values(r) | {
                "test_event_id": event_id,
                "number": r["number"],
                "vehicle_id": vehicle.pk,
                "performer_id": performer.pk if performer else None,
                "test_intent": r["test_intent"],
                "workspace": r["workspace"],
            }
            for role in rec.PERSON_ROLES:
                values[f"{role}_id"] = self._person(r[role])
            clashes = [
                (
                    Shift.objects.filter(test_event_id=event_id, number=r["number"]),
                    f"Shift {r['number']} of this test event already exists here as "
                    f"another shift; numbers are never changed on import",
                )
            ]
            if values["end"] is None:
                clashes.append(
                    (
                        rules.open_shifts_of_vehicle(vehicle.pk),
                        f"Vehicle '{vehicle.key}' already has an open shift here and the "
                        f"archive brings another open one; close one of them first",
                    )
                )
            row = self.save_entry(
                "shifts", Shift, r, values, parent="test_event_id", clashes=clashes
            )
            self.shifts[r["uid"]] = row.pk

    def leg_rows(self):
        for r in self._closed_first(self.records("legs")):
            self.where = f"legs record {r['uid']}"
            shift_id = self._parent(self.shifts, Shift, r["shift"], "shift")
            source = self._config(
                self.pose_sources, PoseSource, r["default_pose_source"], "pose source"
            )
            values = self._entry_values(r) | {
                "shift_id": shift_id,
                "number": r["number"],
                "weather_id": r["weather"],
                "default_pose_source_id": source.pk if source else None,
                "recording": r.get("recording", ""),
            }
            clashes = [
                (
                    Leg.objects.filter(shift_id=shift_id, number=r["number"]),
                    f"Leg {r['number']} of this shift already exists here as another leg; "
                    f"numbers are never changed on import",
                )
            ]
            if values["end"] is None:
                clashes.append(
                    (
                        rules.open_legs_of_shift(shift_id),
                        "This shift already has another open leg here; close it first",
                    )
                )
            self.legs[r["uid"]] = self.save_entry(
                "legs", Leg, r, values, parent="shift_id", clashes=clashes
            ).pk

    def segment_rows(self):
        records = sorted(
            self.records("segments"),
            key=lambda r: (r.get("parent") is not None, r.get("end") is None, r["start"]),
        )
        for r in records:
            self.where = f"segments record {r['uid']}"
            leg_id = self._parent(self.legs, Leg, r["leg"], "leg")
            parent_id = None
            if r.get("parent"):
                parent_id, grandparent, parent_leg = self._segment(r["parent"])
                if grandparent is not None or parent_leg != leg_id:
                    self.refuse(f"{self.where}: its parent is not a master of the same leg.")
            annotation = {
                "ito_reason_id": r["ito_reason"],
                "obstacle": r["obstacle"],
                "lighting": r["lighting"],
                "slope": r["slope"],
            }
            values = {
                "leg_id": leg_id,
                "parent_id": parent_id,
                "segment_type_id": r["segment_type"],
                "start_position": rec.point_in(r["start_position"], "start_position"),
                "start_local_x": r["start_local_x"],
                "start_local_y": r["start_local_y"],
                "start_local_frame": r["start_local_frame"],
                "start": rec.time_in(r["start"], "start"),
                "end": rec.time_in(r["end"], "end"),
                "robot_stamp": rec.time_in(r["robot_stamp"], "robot_stamp"),
            }
            clashes = []
            if parent_id is None and values["end"] is None:
                clashes.append(
                    (
                        rules.open_masters_of_leg(leg_id),
                        "This leg already has another open master segment here; close it first",
                    )
                )
            row = self.save_entry(
                "segments",
                Segment,
                r,
                values,
                parent="leg_id",
                clashes=clashes,
                annotation=annotation,
            )
            self.segments[r["uid"]] = (row.pk, row.parent_id, row.leg_id)

    def _segment(self, uid) -> tuple[int, int | None, int]:
        if uid not in self.segments:
            row = Segment.objects.filter(uid=uid).values_list("pk", "parent_id", "leg_id").first()
            if row is None:
                self.refuse(f"{self.where}: segment {uid} is neither in the archive nor here.")
            self.segments[uid] = row
        return self.segments[uid]

    def _master(self, uid) -> Segment:
        if uid not in self.masters:
            pk, parent_id, _ = self._segment(uid)
            # Data sent for an ITO reason belongs to its master (as when recording).
            self.masters[uid] = Segment(pk=parent_id or pk)
        return self.masters[uid]

    # --- notes and telemetry -------------------------------------------------------------

    def note_rows(self):
        for r in self.records("notes"):
            uid = uuid.UUID(r["uid"])
            created = rec.time_in(r["created"], "created")
            edited = rec.time_in(r["edited"], "edited")
            row = Note.objects.filter(uid=uid).first()
            if row is None:
                row = Note(
                    uid=uid,
                    segment_id=self._segment(r["segment"])[0],
                    author_id=self._person(r["author"]),
                    text=r["text"],
                    created=created,
                    edited=edited,
                )
                row.full_clean(validate_unique=False)
                row.save()
                self.plan.note("notes", "added")
                self.changed.append(row)
            elif edited > row.edited and r["text"] != row.text:
                row.text, row.edited = r["text"], edited
                row.full_clean(validate_unique=False)
                row.save(update_fields=["text", "edited"])
                self.plan.note("notes", "updated")
                self.changed.append(row)
            else:
                self.plan.note("notes", "unchanged")

    def _track(self, table, model, build):
        for batch in _batches(self.records(table), BATCH):
            uids = [uuid.UUID(r["uid"]) for r in batch]
            known = set(model.objects.filter(uid__in=uids).values_list("uid", flat=True))
            fresh = []
            for uid, r in zip(uids, batch, strict=True):
                if uid in known:
                    continue
                self.where = f"{table} record {uid}"
                fresh.append(build(uid, r))
                known.add(uid)
            model.objects.bulk_create(fresh, batch_size=BATCH)
            self.plan.note(table, "added", len(fresh))
            for row in fresh:
                self.track_points[(table, row.segment_id)] += 1
            self.plan.note(table, "unchanged", len(batch) - len(fresh))

    def pose_rows(self):
        def build(uid, r):
            point = r["point"]
            if not isinstance(point, list) or len(point) != 2:
                self.refuse(f"{self.where}: point must be [longitude, latitude].")
            fix = GpsFix(
                longitude=point[0],
                latitude=point[1],
                altitude=r["altitude"],
                fix_status=r["fix_status"],
                horizontal_accuracy=r["horizontal_accuracy"],
                robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
                uid=uid,
            )
            source = self._config(self.pose_sources, PoseSource, r["pose_source"], "pose source")
            return fix.to_pose(
                self._master(r["segment"]), source, rec.time_in(r["received"], "received")
            )

        self._track("poses", Pose, build)

    def local_pose_rows(self):
        def build(uid, r):
            pose = MapPose(
                x=r["x"],
                y=r["y"],
                frame=r["frame"],
                yaw=r["yaw"],
                robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
                uid=uid,
            )
            return pose.to_local_pose(
                self._master(r["segment"]), rec.time_in(r["received"], "received")
            )

        self._track("local_poses", LocalPose, build)

    def _store_file(self, row, record, formats, field="image"):
        """``formats``: the picture formats allowed, or None for a black-box
        snapshot, which must be an MCAP file."""
        name = record["file"]
        content = self.bundle.read_file(name)
        stored = getattr(row, field)
        # The archive's file name is not trusted: the checked format names the file.
        if formats is None:
            if not content.startswith(MCAP_MAGIC):
                raise MalformedRecord(f"{self.where}: the snapshot is not an MCAP file.")
            suffix = "mcap"
        else:
            try:
                suffix = checked_picture(content, formats)
            except ValidationError as exc:
                raise MalformedRecord(f"{self.where}: {_messages(exc)}") from None
        if self.dry_run:
            stored.name = name
            return
        stored.save(f"{PurePosixPath(name).stem}.{suffix}", ContentFile(content), save=False)
        self.written.append((stored.storage, stored.name))

    def map_rows(self):
        for r in self.records("maps"):
            uid = uuid.UUID(r["uid"])
            if MapImage.objects.filter(uid=uid).exists():
                self.plan.note("maps", "unchanged")
                continue
            placement = {name: r[name] for name in MapImage.PLACEMENT_FIELDS if name != "frame"}
            try:
                check_map_placement(**placement)
            except ValidationError as exc:
                self.refuse(f"maps record {uid}: {_messages(exc)}")
            row = MapImage(
                uid=uid,
                shift_id=self._parent(self.shifts, Shift, r["shift"], "shift"),
                **{name: r[name] for name in (*MapImage.PLACEMENT_FIELDS, "checksum")},
                robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
                received=rec.time_in(r["received"], "received"),
            )
            self._store_file(row, r, MAP_FORMATS)
            row.full_clean(validate_unique=False)
            row.save()
            self.plan.note("maps", "added")
            self.changed.append(row)

    def image_rows(self):
        for r in self.records("images"):
            uid = uuid.UUID(r["uid"])
            row = Image.objects.filter(uid=uid).first()
            if row is not None:
                if row.description != r["description"]:
                    row.description = r["description"]
                    row.full_clean(validate_unique=False)
                    row.save(update_fields=["description"])
                    self.plan.note("images", "updated")
                    self.changed.append(row)
                else:
                    self.plan.note("images", "unchanged")
                continue
            row = Image(
                uid=uid,
                # A full row: the file's storage name contains the segment's uid.
                segment=Segment.objects.get(pk=self._master(r["segment"]).pk),
                description=r["description"],
                robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
                received=rec.time_in(r["received"], "received"),
            )
            self._store_file(row, r, PHOTO_FORMATS)
            row.full_clean(validate_unique=False, exclude=["segment"])
            row.save()
            self.plan.note("images", "added")
            self.changed.append(row)

    def recording_rows(self):
        # A snapshot never changes once stored: a known uid is left as it is.
        for r in self.records("recordings"):
            uid = uuid.UUID(r["uid"])
            if Recording.objects.filter(uid=uid).exists():
                self.plan.note("recordings", "unchanged")
                continue
            row = Recording(
                uid=uid,
                segment=Segment.objects.get(pk=self._master(r["segment"]).pk),
                start=rec.time_in(r["start"], "start"),
                end=rec.time_in(r["end"], "end"),
                topics=r["topics"],
                message_count=r["message_count"],
                size=r["size"],
                reason=r["reason"],
                received=rec.time_in(r["received"], "received"),
            )
            self._store_file(row, r, None, field="file")
            row.full_clean(validate_unique=False, exclude=["segment"])
            row.save()
            self.plan.note("recordings", "added")
            self.changed.append(row)

    def run(self):
        self.catalogues()
        self.configuration()
        self.test_events()
        self.basemap_links()
        self.shift_rows()
        self.leg_rows()
        self.segment_rows()
        self.note_rows()
        self.pose_rows()
        self.local_pose_rows()
        self.map_rows()
        self.image_rows()
        self.recording_rows()
        self.nothing_open_under_closed()
        self.announce()

    def announce(self):
        """Open browsers see an import like any other change (same transaction)."""
        for row in self.changed:
            feed.announce_row(row)
        masters = Segment.objects.in_bulk({segment for _, segment in self.track_points})
        for (table, segment), count in self.track_points.items():
            kind = "poses" if table == "poses" else "local_poses"
            # No points inline: the page re-reads the track.
            feed.announce(kind, masters[segment], segment=segment, mode=None, count=count)

    def nothing_open_under_closed(self):
        """Closing cascades down in the services; an import may not leave an open entry
        under a closed one either (a new open leg in a shift closed here, or an archive
        that ends a test event whose shift is still running here)."""
        self.where = "after all records"
        segments = [pk for pk, _, _ in self.segments.values()]
        touched = {Shift: self.shifts.values(), Leg: self.legs.values(), Segment: segments}
        parents = {
            "test_event": self.events.values(),
            "shift": self.shifts.values(),
            "leg": self.legs.values(),
            "parent": segments,
        }
        for model, parent, label in rules.NESTING:
            stranded = (
                rules.open_under_closed(model, parent)
                .filter(
                    Q(pk__in=list(touched[model]))
                    | Q(**{f"{parent}_id__in": list(parents[parent])})
                )
                .select_related(parent)
                .first()
            )
            if stranded is not None:
                self.refuse(
                    f"{label.capitalize()} {stranded.uid} would stay open inside "
                    f"{getattr(stranded, parent)} (uid {getattr(stranded, parent).uid}), "
                    f"which is closed; end the {label} where it is still open and try again."
                )

    def discard_files(self):
        for storage, name in self.written:
            storage.delete(name)
        self.written.clear()


def _later(archived, ours) -> bool:
    return archived is not None and (ours is None or archived > ours)


def _messages(exc: ValidationError) -> str:
    if hasattr(exc, "error_dict"):
        return "; ".join(f"{k}: {' '.join(v)}" for k, v in exc.message_dict.items())
    return " ".join(exc.messages)


def import_bundle(bundle, *, dry_run: bool = False) -> Plan:
    """Apply a verified archive (or any object with ``records(table)`` and
    ``read_file(name)``).  Raises :class:`ImportRefused`; then nothing changed."""
    importer = _Importer(bundle, dry_run)
    try:
        with transaction.atomic():
            importer.run()
            if dry_run:
                transaction.set_rollback(True)
    except ImportRefused as exc:
        importer.discard_files()
        raise type(exc)(f"{exc} Nothing was imported.") from None
    except ValidationError as exc:
        importer.discard_files()
        raise ImportRefused(f"{importer.where}: {_messages(exc)}. Nothing was imported.") from None
    except (
        ArchiveError,
        rec.RecordError,
        LookupError,
        AttributeError,
        TypeError,
        ValueError,
        OverflowError,
    ) as exc:
        importer.discard_files()
        what = f"missing field {exc}" if isinstance(exc, KeyError) else str(exc)
        raise MalformedRecord(
            f"{importer.where}: malformed record ({what}). Nothing was imported."
        ) from None
    except (IntegrityError, DatabaseError) as exc:
        importer.discard_files()
        raise ImportRefused(
            f"{importer.where}: the database refused it ({str(exc).strip()}). Nothing was imported."
        ) from None
    except BaseException:
        importer.discard_files()
        raise
    return importer.plan
