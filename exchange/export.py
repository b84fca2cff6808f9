"""Writing test events, with everything recorded in them, into an archive."""

import os
import socket
import uuid
from dataclasses import dataclass
from datetime import datetime

from django.db import connection
from django.db.models import Q
from django.utils.translation import gettext as _

from basemaps.models import EventBasemap
from events.models import (
    ItoReason,
    Judgement,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    SegmentType,
    Shift,
    TestCase,
    TestEvent,
    Vehicle,
    Weather,
)
from exchange import records as rec
from exchange.archive import ArchiveWriter
from exchange.history_records import HistoryExport
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.storage import keys

BATCH = 5000


class ExportError(Exception):
    pass


@dataclass
class ExportResult:
    path: str
    counts: dict
    files: int


def select_events(
    uids_or_ids: list[str] | None = None, since: datetime | None = None
) -> list[TestEvent]:
    """Events named by uid or id; without names, every event (changed since ``since``)."""
    if uids_or_ids:
        events = []
        for ident in uids_or_ids:
            try:
                lookup = Q(pk=int(ident)) if ident.isdigit() else Q(uid=uuid.UUID(ident))
                events.append(TestEvent.objects.get(lookup))
            except (TestEvent.DoesNotExist, ValueError):
                raise ExportError(
                    _("No test event with id or uid '%(ident)s'.") % {"ident": ident}
                ) from None
        return events
    events = TestEvent.objects.all()
    if since is not None:
        # An event that ended before `since` counts only if something in it was
        # recorded, noted or edited since.
        # One query per table: OR-ing the reverse joins would multiply the rows.
        in_segment = "segment__leg__shift__test_event"
        touched = set()
        for model, stamp, event in (
            (Pose, "received", in_segment),
            (LocalPose, "received", in_segment),
            (Image, "received", in_segment),
            (Recording, "received", in_segment),
            (Note, "edited", in_segment),
            (MapImage, "received", "shift__test_event"),
            (Shift, "modified", "test_event"),
            (Leg, "modified", "shift__test_event"),
            (Segment, "modified", "leg__shift__test_event"),
        ):
            touched |= set(
                model.objects.filter(**{f"{stamp}__gte": since})
                .values_list(event, flat=True)
                .distinct()
            )
        events = events.filter(
            Q(end__isnull=True)
            | Q(end__gte=since)
            | Q(start__gte=since)
            | Q(modified__gte=since)
            | Q(pk__in=touched)
        )
    return list(events.order_by("start", "id"))


def export_events(path, events: list[TestEvent], *, since: datetime | None = None) -> ExportResult:
    event_ids = [e.pk for e in events]
    shifts = list(
        Shift.objects.filter(test_event_id__in=event_ids)
        .select_related(
            "test_event",
            "vehicle",
            "performer",
            *rec.PERSON_ROLES,
        )
        .order_by("start", "id")
    )
    legs = list(
        Leg.objects.filter(shift__test_event_id__in=event_ids)
        .select_related("shift", "default_pose_source", "test_case")
        .order_by("start", "id")
    )
    # Masters before children so that an importer always meets the parent first.
    segments = list(
        Segment.objects.filter(leg__shift__test_event_id__in=event_ids).order_by(
            "parent_id", "start", "id"
        )
    )
    segments.sort(key=lambda s: (s.parent_id is not None, s.start, s.pk))
    uids = {("leg", leg.pk): str(leg.uid) for leg in legs}
    uids |= {("segment", s.pk): str(s.uid) for s in segments}
    segment_uid = {s.pk: str(s.uid) for s in segments}
    segment_ids = list(segment_uid)
    notes = list(
        Note.objects.filter(segment_id__in=segment_ids)
        .select_related("author")
        .order_by("created", "id")
    )
    telemetry = Q(segment_id__in=segment_ids)
    if since is not None:
        telemetry &= Q(received__gte=since)
    maps = MapImage.objects.filter(shift__test_event_id__in=event_ids).select_related("shift")
    if since is not None:
        maps = maps.filter(received__gte=since)
    maps = list(maps.order_by("received", "id"))
    images = list(Image.objects.filter(telemetry).order_by("received", "id"))
    recordings = list(Recording.objects.filter(telemetry).order_by("received", "id"))
    stored = [row.image for row in [*maps, *images]] + [row.file for row in recordings]
    missing = [f.name for f in stored if not f.name or not f.storage.exists(f.name)]
    if missing:
        raise ExportError(
            _(
                "%(count)s image, map or snapshot file(s) are missing from media "
                "storage, e.g. %(missing)s; restore them or delete those rows before "
                "exporting."
            )
            % {"count": len(missing), "missing": missing[0]}
        )

    history = HistoryExport(
        {
            "test_event": event_ids,
            "shift": [s.pk for s in shifts],
            "leg": [leg.pk for leg in legs],
            "segment": segment_ids,
            "note": [n.pk for n in notes],
            "image": [i.pk for i in images],
        },
        since,
    )
    people = {s_person for s in shifts for r in rec.PERSON_ROLES if (s_person := getattr(s, r))}
    people |= {n.author for n in notes if n.author}
    people |= set(Personnel.objects.filter(pk__in=history.ids_of(Personnel)))
    source_ids = {leg.default_pose_source_id for leg in legs if leg.default_pose_source_id}
    source_ids |= history.ids_of(PoseSource)
    source_ids |= set(
        Pose.objects.filter(telemetry, pose_source__isnull=False)
        .values_list("pose_source_id", flat=True)
        .distinct()
    )
    source_key = dict(PoseSource.objects.filter(pk__in=source_ids).values_list("pk", "key"))

    selection = {
        "test_events": [str(e.uid) for e in events],
        "since": rec.time_out(since),
        "source": {"host": socket.gethostname(), "database": connection.vendor},
    }
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with ArchiveWriter(path, selection=selection) as out:
        out.write_records("weather", map(rec.catalogue_record, Weather.objects.order_by("key")))
        out.write_records(
            "segment_types", map(rec.catalogue_record, SegmentType.objects.order_by("key"))
        )
        out.write_records(
            "ito_reasons", map(rec.catalogue_record, ItoReason.objects.order_by("key"))
        )
        vehicle_ids = {s.vehicle_id for s in shifts} | history.ids_of(Vehicle)
        out.write_records(
            "vehicles",
            (
                rec.keyed_record(v, "institution", "configuration", "vin")
                for v in Vehicle.objects.filter(pk__in=vehicle_ids).order_by("key")
            ),
        )
        out.write_records(
            "pose_sources",
            (rec.keyed_record(p) for p in PoseSource.objects.filter(pk__in=source_ids)),
        )
        performer_ids = {s.performer_id for s in shifts if s.performer_id}
        performer_ids |= history.ids_of(Performer)
        out.write_records(
            "performers",
            (
                {"institution": p.institution}
                for p in Performer.objects.filter(pk__in=performer_ids).order_by("institution")
            ),
        )
        out.write_records(
            "personnel",
            (
                {"ref": rec.person_ref(p), "name": p.name, "institution": p.institution}
                for p in Personnel.objects.filter(pk__in={p.pk for p in people}).order_by("pk")
            ),
        )
        out.write_records("test_events", map(rec.test_event_record, events))
        out.write_records(
            "basemaps",
            map(
                rec.basemap_record,
                EventBasemap.objects.filter(test_event_id__in=event_ids)
                .select_related("test_event", "layer")
                .order_by("test_event__start", "test_event_id"),
            ),
        )
        out.write_records(
            "test_cases",
            map(
                rec.test_case_record,
                TestCase.objects.filter(test_event_id__in=event_ids)
                .select_related("test_event")
                .prefetch_related("criteria__reasons")
                .order_by("test_event_id", "key"),
            ),
        )
        out.write_records("shifts", map(rec.shift_record, shifts))
        out.write_records("legs", map(rec.leg_record, legs))
        out.write_records(
            "judgements",
            (
                rec.judgement_record(j, uids["leg", j.leg_id] if j.leg_id else None)
                for j in Judgement.objects.filter(criterion__test_case__test_event_id__in=event_ids)
                .select_related("criterion__test_case__test_event")
                .order_by("id")
            ),
        )
        out.write_records("segments", (rec.segment_record(s, uids) for s in segments))
        out.write_records("notes", (rec.note_record(n, segment_uid[n.segment_id]) for n in notes))
        out.write_records(
            "poses",
            (
                rec.pose_record(p, segment_uid[p.segment_id], source_key.get(p.pose_source_id))
                for p in Pose.objects.filter(telemetry)
                .order_by("segment_id", *keys.order_by())
                .iterator(chunk_size=BATCH)
            ),
        )
        out.write_records(
            "local_poses",
            (
                rec.local_pose_record(p, segment_uid[p.segment_id])
                for p in LocalPose.objects.filter(telemetry)
                .order_by("segment_id", *keys.order_by())
                .iterator(chunk_size=BATCH)
            ),
        )
        out.write_records("maps", map(rec.map_record, maps))
        out.write_records(
            "images", (rec.image_record(i, segment_uid[i.segment_id]) for i in images)
        )
        out.write_records(
            "recordings",
            (rec.recording_record(r, segment_uid[r.segment_id]) for r in recordings),
        )
        out.write_records("history", history.records())
        for stored_file in stored:
            with stored_file.open("rb") as handle:
                out.write_file(stored_file.name, handle)
        files = sum(1 for name in out.members if name.startswith("files/"))
        counts = dict(out.counts)
    return ExportResult(path=str(path), counts=counts, files=files)
