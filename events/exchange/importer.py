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
inside one transaction, after ``full_clean`` and the checks above; the database
constraints stay the last guard.  Files written before a failure are removed.
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

from events.exchange import records as rec
from events.exchange.archive import ArchiveError
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
from telemetry.models import Image, LocalPose, MapImage, Pose
from telemetry.services.recording import GpsFix, MapPose

BATCH = 2000
OUTCOMES = ("added", "updated", "unchanged", "reused")
CATALOGUES = {"weather": Weather, "segment_types": SegmentType, "ito_reasons": ItoReason}


class ImportRefused(Exception):
    """The data cannot be imported as it is; nothing was changed."""


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

    # --- reading -------------------------------------------------------------------------

    def records(self, table: str):
        for record in self.bundle.records(table):
            self.where = f"{table} record {record.get('uid') or record.get('key') or ''}".strip()
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
                        Shift.objects.filter(vehicle=vehicle, end__isnull=True),
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
                        Leg.objects.filter(shift_id=shift_id, end__isnull=True),
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
                        Segment.objects.filter(
                            leg_id=leg_id, parent__isnull=True, end__isnull=True
                        ),
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
            elif edited > row.edited and r["text"] != row.text:
                row.text, row.edited = r["text"], edited
                row.full_clean(validate_unique=False)
                row.save(update_fields=["text", "edited"])
                self.plan.note("notes", "updated")
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

    def _store_file(self, row, record):
        name = record["file"]
        content = self.bundle.read_file(name)
        if self.dry_run:
            row.image.name = name
            return
        row.image.save(PurePosixPath(name).name, ContentFile(content), save=False)
        self.written.append((row.image.storage, row.image.name))

    def map_rows(self):
        for r in self.records("maps"):
            uid = uuid.UUID(r["uid"])
            if MapImage.objects.filter(uid=uid).exists():
                self.plan.note("maps", "unchanged")
                continue
            row = MapImage(
                uid=uid,
                shift_id=self._parent(self.shifts, Shift, r["shift"], "shift"),
                **{name: r[name] for name in (*MapImage.PLACEMENT_FIELDS, "checksum")},
                robot_stamp=rec.time_in(r["robot_stamp"], "robot_stamp"),
                received=rec.time_in(r["received"], "received"),
            )
            self._store_file(row, r)
            row.full_clean(validate_unique=False)
            row.save()
            self.plan.note("maps", "added")

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
            self._store_file(row, r)
            row.full_clean(validate_unique=False, exclude=["segment"])
            row.save()
            self.plan.note("images", "added")

    def run(self):
        self.catalogues()
        self.configuration()
        self.test_events()
        self.shift_rows()
        self.leg_rows()
        self.segment_rows()
        self.note_rows()
        self.pose_rows()
        self.local_pose_rows()
        self.map_rows()
        self.image_rows()
        self.nothing_open_under_closed()

    def nothing_open_under_closed(self):
        """Closing cascades down in the services; an import may not leave an open entry
        under a closed one either (a new open leg in a shift closed here, or an archive
        that ends a test event whose shift is still running here)."""
        self.where = "after all records"
        segments = [pk for pk, _, _ in self.segments.values()]
        checks = [
            (Shift, "test_event", self.shifts.values(), self.events.values(), "shift"),
            (Leg, "shift", self.legs.values(), self.shifts.values(), "leg"),
            (Segment, "leg", segments, self.legs.values(), "segment"),
            (Segment, "parent", segments, segments, "ITO reason"),
        ]
        for model, parent, touched, parents, label in checks:
            stranded = (
                model.objects.filter(end__isnull=True, **{f"{parent}__end__isnull": False})
                .filter(Q(pk__in=list(touched)) | Q(**{f"{parent}_id__in": list(parents)}))
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
        raise ImportRefused(f"{exc} Nothing was imported.") from None
    except ValidationError as exc:
        importer.discard_files()
        raise ImportRefused(f"{importer.where}: {_messages(exc)}. Nothing was imported.") from None
    except (ArchiveError, rec.RecordError, KeyError, TypeError, ValueError) as exc:
        importer.discard_files()
        what = f"missing field {exc}" if isinstance(exc, KeyError) else str(exc)
        raise ImportRefused(
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
