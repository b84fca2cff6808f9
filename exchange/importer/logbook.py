"""Importing log entries (test events, shifts, legs, segments) and notes, and the
check that none stays open inside a closed one."""

import uuid

from django.core.exceptions import PermissionDenied, ValidationError
from django.db.models import Q
from django.utils.translation import gettext as _

from basemaps.models import BasemapLayer, EventBasemap
from basemaps.services import layers as basemap_layers
from events import rules
from events.models import (
    Leg,
    Note,
    Performer,
    PoseSource,
    Segment,
    Shift,
    TestCase,
    TestEvent,
    Vehicle,
)
from events.services import finality
from exchange import records as rec
from exchange.importer import plans
from exchange.importer.plan import MalformedRecord
from exchange.importer.session import ImportSession
from telemetry.models import Image, MapImage, Recording

# Segment attributes of the annotation, as stored (the reason by its key).
ANNOTATION_COLUMNS = tuple(Segment._meta.get_field(f).attname for f in Segment.ANNOTATION_FIELDS)


def save_entry(
    session: ImportSession,
    table,
    model,
    record,
    values,
    *,
    parent=None,
    clashes=(),
    annotation=None,
    counters=None,
    settled=None,
):
    """Add or update one log entry.

    ``clashes`` are (queryset, message) pairs that must be empty before a new
    entry may be added.  ``annotation`` holds a segment's reason fields: they
    follow their own stamp (``annotated``), so that an operator's annotation
    survives the robot closing the same segment later on the other side.
    ``counters`` only ever grow where they are counted (a leg's missed fixes,
    added without a change stamp): the larger count wins.  ``settled`` holds
    values that are set once and then kept (a test event's finalisation): the
    archive's are taken while the first of them is still empty here.
    """
    uid = uuid.UUID(record["uid"])
    # A record without change stamps (an archive of an older FTT): the
    # archive's copy is taken.
    modified = rec.time_in(record.get("modified"), "modified")
    annotated = rec.time_in(record.get("annotated"), "annotated")
    annotation = annotation or {}
    counters = counters or {}
    settled = settled or {}
    row = model.objects.filter(uid=uid).first()
    if row is None:
        values = values | counters | settled
        for queryset, message in clashes:
            other = queryset.first()
            if other is not None:
                session.refuse(f"{message} (here: uid {other.uid}; archive: uid {uid}).")
        row = model(uid=uid, **values, **annotation)
        if modified is not None:
            row.modified = modified
        if annotation:
            row.annotated = annotated
        row.full_clean(validate_unique=False, validate_constraints=False)
        row.save(keep_modified=modified is not None)
        session.plan.note(table, "added")
        session.changed.append(row)
        return row
    if parent and getattr(row, parent) != values[parent]:
        session.refuse(
            f"{session.where}: this entry hangs under a different parent here than in "
            f"the archive; the two installations disagree about uid {uid}."
        )
    values.pop("number", None)
    wanted = {}
    # A copy not newer than ours was made before our latest change: a stale
    # archive must not undo what was recorded later.
    if modified is None or modified > row.modified:
        if row.end is not None and values.get("end", row.end) is None:
            values["end"] = row.end  # never re-open; see exchange.importer
        wanted |= values
    wanted |= {name: n for name, n in counters.items() if n > getattr(row, name)}
    if settled and getattr(row, next(iter(settled))) in (None, ""):
        wanted |= settled
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
    session.plan.note(table, "updated" if changed else "unchanged")
    if changed:
        session.changed.append(row)
    return row


def _later(archived, ours) -> bool:
    return archived is not None and (ours is None or archived > ours)


def _entry_values(record) -> dict:
    return {
        "start": rec.time_in(record["start"], "start"),
        "end": rec.time_in(record["end"], "end"),
        "note": record.get("note", ""),
    }


def _closed_first(records) -> list:
    # Entries that end are applied before open ones, so that closing an old
    # shift makes room for the archive's newer open shift.
    return sorted(records, key=lambda r: (r.get("end") is None, r["start"]))


def import_test_events(session: ImportSession):
    for r in session.records("test_events"):
        values = _entry_values(r) | {
            "location": r["location"],
            "version": r["version"],
            "time_zone": r["time_zone"],
            # Archives written before reports had a language are English.
            "language": r.get("language", "en"),
        }
        final = _finalisation(session, r)
        was_final = TestEvent.objects.filter(uid=r["uid"], finalised__isnull=False).exists()
        event = save_entry(session, "test_events", TestEvent, r, values, settled=final)
        if event.finalised is not None and not was_final:
            # Its rows come with its finalisation: what was final there.
            session.arriving.add(event.pk)
        if event.finalised is not None and event.end is None:
            message = _("the test event is final in the archive but open here; close it here")
            session.refuse(f"{session.where}: {message}.")
        session.events[r["uid"]] = event.pk


def _finalisation(session: ImportSession, record) -> dict:
    """A final event stays final with its frozen taxonomy; archives of an older
    FTT, or of an event not final there, bring none."""
    finalised = rec.time_in(record.get("finalised"), "finalised")
    if finalised is None:
        return {}
    if not isinstance(record.get("taxonomy"), dict):
        message = _("a final test event without its taxonomy")
        raise MalformedRecord(f"{session.where}: {message}.")
    return {
        "finalised": finalised,
        "finalised_by": str(record.get("finalised_by") or ""),
        "taxonomy": record["taxonomy"],
    }


def link_basemaps(session: ImportSession):
    """Each test event's default basemap, where its layer is here or is a URL."""
    for r in session.records("basemaps"):
        event_id = session.entry_id(session.events, TestEvent, r["test_event"], "test event")
        layer = BasemapLayer.objects.filter(key=r["key"]).first()
        if layer is None and r.get("kind") == BasemapLayer.URL:
            layer = basemap_layers.register_url(
                r["url"],
                name=r["name"],
                attribution=r.get("attribution", ""),
                max_zoom=r.get("max_zoom", 19),
                key=r["key"],
                # An address from an archive is not yet one an administrator checked.
                enabled=False,
            )
        if layer is None:
            # The file is not here; a backup, not an archive, moves basemap files.
            session.plan.note("basemaps", "unchanged")
            continue
        current = EventBasemap.objects.filter(test_event_id=event_id).first()
        if current is not None and current.layer_id == layer.pk:
            session.plan.note("basemaps", "unchanged")
            continue
        basemap_layers.set_event_default(TestEvent(pk=event_id), layer)
        session.plan.note("basemaps", "added" if current is None else "updated")


def import_shifts(session: ImportSession):
    for r in _closed_first(session.records("shifts")):
        session.where = f"shifts record {r['uid']}"
        event_id = session.entry_id(session.events, TestEvent, r["test_event"], "test event")
        vehicle = session.config_row(session.vehicles, Vehicle, r["vehicle"], "vehicle")
        performer = session.config_row(session.performers, Performer, r["performer"], "performer")
        values = _entry_values(r) | {
            "test_event_id": event_id,
            "number": r["number"],
            "vehicle_id": vehicle.pk,
            "performer_id": performer.pk if performer else None,
            "test_intent": r["test_intent"],
            "workspace": r["workspace"],
        }
        for role in rec.PERSON_ROLES:
            values[f"{role}_id"] = session.person_id(r[role])
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
        row = save_entry(
            session, "shifts", Shift, r, values, parent="test_event_id", clashes=clashes
        )
        session.shifts[r["uid"]] = row.pk


def import_legs(session: ImportSession):
    for r in _closed_first(session.records("legs")):
        session.where = f"legs record {r['uid']}"
        shift_id = session.entry_id(session.shifts, Shift, r["shift"], "shift")
        source = session.config_row(
            session.pose_sources, PoseSource, r["default_pose_source"], "pose source"
        )
        values = _entry_values(r) | {
            "shift_id": shift_id,
            "number": r["number"],
            "weather_id": r["weather"],
            "default_pose_source_id": source.pk if source else None,
            "recording": r.get("recording", ""),
        }
        if "test_case" in r:  # archives from before test plans lack it
            values["test_case_id"] = plans.test_case_id(session, shift_id, r["test_case"])
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
        # Archives from before the count lack it: nothing to add.
        counters = {"fixes_missed": r["fixes_missed"]} if "fixes_missed" in r else {}
        session.legs[r["uid"]] = save_entry(
            session, "legs", Leg, r, values, parent="shift_id", clashes=clashes, counters=counters
        ).pk


def import_segments(session: ImportSession):
    records = sorted(
        session.records("segments"),
        key=lambda r: (r.get("parent") is not None, r.get("end") is None, r["start"]),
    )
    for r in records:
        session.where = f"segments record {r['uid']}"
        leg_id = session.entry_id(session.legs, Leg, r["leg"], "leg")
        parent_id = None
        if r.get("parent"):
            parent = session.segment(r["parent"])
            parent_id = parent.pk
            if not parent.is_master or parent.leg_id != leg_id:
                session.refuse(f"{session.where}: its parent is not a master of the same leg.")
        # Archives from before the regulator fields lack them: defaults.
        annotation = {
            column: r.get(name, Segment._meta.get_field(name).get_default())
            for name, column in zip(Segment.ANNOTATION_FIELDS, ANNOTATION_COLUMNS, strict=True)
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
        # Archives from before these fields lack them: what is here stays.
        if "suggested_reason" in r:
            values["suggested_reason_id"] = r["suggested_reason"]
        if "start_uncertainty" in r:
            values["start_uncertainty"] = r["start_uncertainty"]
        clashes = []
        if parent_id is None and values["end"] is None:
            clashes.append(
                (
                    rules.open_masters_of_leg(leg_id),
                    "This leg already has another open master segment here; close it first",
                )
            )
        session.segments[r["uid"]] = save_entry(
            session,
            "segments",
            Segment,
            r,
            values,
            parent="leg_id",
            clashes=clashes,
            annotation=annotation,
        )


def import_notes(session: ImportSession):
    for r in session.records("notes"):
        uid = uuid.UUID(r["uid"])
        created = rec.time_in(r["created"], "created")
        edited = rec.time_in(r["edited"], "edited")
        segment_id = session.segment(r["segment"]).pk
        row = session.stored("notes", Note, uid, segment_id=segment_id)
        if row is None:
            row = Note(
                uid=uid,
                segment_id=segment_id,
                author_id=session.person_id(r["author"]),
                text=r["text"],
                created=created,
                edited=edited,
            )
            row.full_clean(validate_unique=False)
            row.save()
            session.plan.note("notes", "added")
            session.changed.append(row)
        elif edited > row.edited and r["text"] != row.text:
            row.text, row.edited = r["text"], edited
            row.full_clean(validate_unique=False)
            row.save(update_fields=["text", "edited"])
            session.plan.note("notes", "updated")
            session.changed.append(row)
        else:
            session.plan.note("notes", "unchanged")


# How a row the import wrote finds its test event.
_EVENT_PATHS = (
    ((TestEvent,), "pk", "pk"),
    ((Shift, TestCase), "test_event_id", "pk"),
    ((Leg, MapImage), "shift_id", "shifts"),
    ((Segment,), "leg_id", "shifts__legs"),
    ((Note, Image, Recording), "segment_id", "shifts__legs__segments"),
)


def refuse_changes_to_final(session: ImportSession):
    """An archive adds nothing to a test event final here and changes nothing in
    it (events.services.finality), unless the archive makes it final itself."""
    session.where = "after all records"
    touched = Q(shifts__legs__segments__in={segment for _, segment in session.track_points})
    for models, attribute, path in _EVENT_PATHS:
        ids = {getattr(row, attribute) for row in session.changed if isinstance(row, models)}
        if ids:
            touched |= Q(**{f"{path}__in": ids})
    try:
        finality.require_amendable(touched)
    except (ValidationError, PermissionDenied) as exc:
        session.refuse(" ".join(getattr(exc, "messages", None) or [str(exc)]))


def refuse_open_under_closed(session: ImportSession):
    """Closing cascades down in the services; an import may not leave an open entry
    under a closed one either (a new open leg in a shift closed here, or an archive
    that ends a test event whose shift is still running here)."""
    session.where = "after all records"
    segments = [s.pk for s in session.segments.values()]
    touched = {Shift: session.shifts.values(), Leg: session.legs.values(), Segment: segments}
    parents = {
        "test_event": session.events.values(),
        "shift": session.shifts.values(),
        "leg": session.legs.values(),
        "parent": segments,
    }
    for model, parent, label in rules.NESTING:
        stranded = (
            rules.open_under_closed(model, parent)
            .filter(
                Q(pk__in=list(touched[model])) | Q(**{f"{parent}_id__in": list(parents[parent])})
            )
            .select_related(parent)
            .first()
        )
        if stranded is not None:
            session.refuse(
                f"{label.capitalize()} {stranded.uid} would stay open inside "
                f"{getattr(stranded, parent)} (uid {getattr(stranded, parent).uid}), "
                f"which is closed; end the {label} where it is still open and try again."
            )
