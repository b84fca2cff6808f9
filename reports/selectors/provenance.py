"""What a report was built from, so that it can be checked later.

The digest covers the canonical content of every row in a test event's scope:
values as people and figures see them, keyed by uid and catalogue keys, never
database ids or file bytes, so the same data gives the same digest on any
installation (after export and import too).  Poses are covered by their uids,
through the uid sums their segments' figures keep (common.uid_sums), so the
digest reads no pose: poses are only ever added, never changed, and thinning
old ones (reports.services.pose_retention) leaves the sums as they were.
Reports of earlier versions hashed the uids read from the poses; a digest
of that kind verifies too.  The report carries the digest, its
build time and the event's uid (PDF keywords, JSON fields), and is sealed
with this installation's key (an HMAC over the whole file: a PDF's bytes, a
JSON report's canonical text), so that a stamp copied into another file, a
second stamp or any edit of the document is refused.  :func:`verify` checks
the seal, recomputes the digest and, when it differs, lists what the change
history says changed since.
"""

import hashlib
import json
import re
from collections import defaultdict
from dataclasses import dataclass, field
from datetime import UTC, datetime

from django.conf import settings
from django.db.models import FileField
from django.utils import timezone
from django.utils.crypto import constant_time_compare, salted_hmac
from django.utils.translation import gettext as _

from common import uid_sums
from events.models import Leg, Note, Segment, Shift, TestEvent
from events.selectors.history import KINDS, author_of, entries_since, word_for
from events.selectors.taxonomy import taxonomy_of, taxonomy_version
from reports.selectors.statistics import event_statistics
from telemetry.models import Image, LocalPose, Pose, SegmentFigures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK

DIGEST_PREFIX = "ftt-digest-sha256-"
BUILT_PREFIX = "ftt-built-"
EVENT_PREFIX = "ftt-event-"
_STAMP_FORMAT = "%Y%m%dT%H%M%S.%fZ"
# The seal's line after a PDF's end (a PDF reader ignores what follows %%EOF).
SEAL_PREFIX = b"%ftt-seal-hmac-sha256-"
_SEAL_LINE = re.compile(rb"\n" + re.escape(SEAL_PREFIX) + rb"([0-9a-f]{64})\n\Z")
_SEAL_SALT = "ftt.reports.seal"


def ftt_version() -> str:
    return settings.SPECTACULAR_SETTINGS["VERSION"]


def _text(value) -> str | None:
    if value is None:
        return None
    if isinstance(value, datetime):
        return value.astimezone(UTC).isoformat(timespec="microseconds").replace("+00:00", "Z")
    return str(value)


def _uid(row) -> str | None:
    return None if row is None else str(row.uid)


def _point(point) -> list[str] | None:
    return None if point is None else [f"{point.x:.9f}", f"{point.y:.9f}"]


def _person(person) -> str | None:
    return None if person is None else f"{person.name}|{person.institution}"


def canonical_records(event: TestEvent, *, legacy: bool = False) -> list[tuple[str, str, dict]]:
    """(table, uid, content) of every row in the event's scope, in a fixed order."""
    records = [
        (
            "test_event",
            str(event.uid),
            {
                "location": event.location,
                "version": event.version,
                "time_zone": event.time_zone,
                "note": event.note,
                "start": _text(event.start),
                "end": _text(event.end),
                "taxonomy": taxonomy_of(event),
            },
        )
    ]
    people = ("test_administrator", "test_director", "safety_officer", "robot_operator")
    for shift in Shift.objects.filter(test_event=event).select_related(
        "vehicle", "performer", *people
    ):
        content = {
            "number": shift.number,
            "vehicle": shift.vehicle.key,
            "performer": shift.performer.institution if shift.performer else None,
            "test_intent": shift.test_intent,
            "workspace": shift.workspace,
            "note": shift.note,
            "start": _text(shift.start),
            "end": _text(shift.end),
        }
        content.update({name: _person(getattr(shift, name)) for name in people})
        records.append(("shift", str(shift.uid), content))
    for leg in Leg.objects.filter(shift__test_event=event).select_related(
        "shift", "default_pose_source"
    ):
        records.append(
            (
                "leg",
                str(leg.uid),
                {
                    "shift": str(leg.shift.uid),
                    "number": leg.number,
                    "weather": leg.weather_id,
                    "pose_source": leg.default_pose_source.key if leg.default_pose_source else None,
                    "recording": leg.recording,
                    "note": leg.note,
                    "start": _text(leg.start),
                    "end": _text(leg.end),
                },
            )
        )
    segments = Segment.objects.filter(leg__shift__test_event=event).select_related("leg", "parent")
    for s in segments:
        records.append(
            (
                "segment",
                str(s.uid),
                {
                    "leg": str(s.leg.uid),
                    "parent": _uid(s.parent),
                    "type": s.segment_type_id,
                    "reason": s.ito_reason_id,
                    "obstacle": s.obstacle,
                    "lighting": s.lighting,
                    "slope": s.slope,
                    "initiator": s.initiator,
                    "severity": s.severity,
                    "location_type": s.location_type,
                    "start": _text(s.start),
                    "end": _text(s.end),
                    "start_position": _point(s.start_position),
                },
            )
        )
    in_event = {"segment__leg__shift__test_event": event}
    for note in Note.objects.filter(**in_event).select_related("segment", "author"):
        records.append(
            (
                "note",
                str(note.uid),
                {
                    "segment": str(note.segment.uid),
                    "author": _person(note.author),
                    "text": note.text,
                },
            )
        )
    for image in Image.objects.filter(**in_event).select_related("segment"):
        records.append(
            (
                "image",
                str(image.uid),
                {"segment": str(image.segment.uid), "description": image.description},
            )
        )
    records += (legacy_pose_records if legacy else pose_records)(event)
    return sorted(records, key=lambda r: (r[0], r[1]))


def pose_records(event: TestEvent) -> list[tuple[str, str, dict]]:
    """The event's poses by the uid sums their segments' figures keep."""
    records = []
    for table, mode in (("poses", GPS_TRACK), ("local_poses", LOCAL_TRACK)):
        kept = SegmentFigures.objects.filter(segment__leg__shift__test_event=event, mode=mode)
        total = uid_sums.combined(*kept.values_list("uid_sum", flat=True))
        records.append((table, "all", {"uid_sum": total}))
    return records


def legacy_pose_records(event: TestEvent) -> list[tuple[str, str, dict]]:
    """The event's poses as reports stamped before the figures kept uid sums
    covered them: a hash of every uid read from the poses, sorted."""
    records = []
    for table, model in (("poses", Pose), ("local_poses", LocalPose)):
        rows = model.objects.filter(segment__leg__shift__test_event=event)
        uids = sorted(str(u) for u in rows.values_list("uid", flat=True))
        records.append(
            (table, "all", {"uids": hashlib.sha256("\n".join(uids).encode()).hexdigest()})
        )
    return records


def data_digest(event: TestEvent, *, legacy: bool = False) -> str:
    """SHA-256 of the event's canonical records (``legacy``: with the poses as
    reports of earlier FTT versions covered them)."""
    digest = hashlib.sha256()
    for table, uid, content in canonical_records(event, legacy=legacy):
        line = json.dumps([table, uid, content], sort_keys=True, ensure_ascii=False)
        digest.update(line.encode() + b"\n")
    return digest.hexdigest()


def provenance(event: TestEvent, options: dict, built: datetime) -> dict:
    """What every report states about its data (PDF and JSON)."""
    amendments = amendments_of(event)
    return {
        "digest": data_digest(event),
        "built": built.astimezone(UTC).strftime(_STAMP_FORMAT),
        "event_uid": str(event.uid),
        "taxonomy": taxonomy_version(event),
        "ftt_version": ftt_version(),
        "options": options,
        "final": _text(event.finalised),
        "amendments": amendments,
    }


def keywords(stamp: dict) -> list[str]:
    """The PDF keywords that carry the stamp (read back by :func:`stamp_of_pdf`)."""
    return [
        DIGEST_PREFIX + stamp["digest"],
        BUILT_PREFIX + stamp["built"],
        EVENT_PREFIX + stamp["event_uid"],
    ]


class TwoStamps(ValueError):
    """A file carries more than one stamp: none of them speaks for it."""


def stamp_of_pdf(pdf: bytes) -> dict | None:
    """The stamp written by :func:`keywords` (typst keeps them as plain text in the
    document information and its XMP metadata, the same twice); TwoStamps when
    the file holds two different ones."""
    found = {}
    for name, prefix, pattern in (
        ("digest", DIGEST_PREFIX, rb"[0-9a-f]{64}"),
        ("built", BUILT_PREFIX, rb"\d{8}T\d{6}\.\d{6}Z"),
        ("event_uid", EVENT_PREFIX, rb"[0-9a-f-]{36}"),
    ):
        values = set(re.findall(re.escape(prefix.encode()) + b"(" + pattern + b")", pdf))
        if not values:
            return None
        if len(values) > 1:
            raise TwoStamps(name)
        found[name] = values.pop().decode()
    return found


def _seal_of(content: bytes, key: str | None = None) -> str:
    key = key or settings.REPORT_SEAL_KEY
    return salted_hmac(_SEAL_SALT, content, secret=key, algorithm="sha256").hexdigest()


def _sealed(seal, content: bytes) -> bool:
    """Is ``seal`` this installation's, or a trusted installation's, over ``content``?"""
    keys = [settings.REPORT_SEAL_KEY, *settings.TRUSTED_SEAL_KEYS]
    return isinstance(seal, str) and any(
        constant_time_compare(seal, _seal_of(content, key)) for key in keys
    )


def seal_pdf(pdf: bytes) -> bytes:
    """``pdf`` with this installation's seal over all its bytes on a last line."""
    return pdf + b"\n" + SEAL_PREFIX + _seal_of(pdf).encode() + b"\n"


def _canonical(document: dict) -> bytes:
    return json.dumps(document, sort_keys=True, ensure_ascii=False).encode()


def _unsealed(content: bytes) -> tuple[dict | None, bool]:
    """The stamp of a PDF or JSON report (``json_report``) and whether this
    installation's seal covers the whole file."""
    if content.startswith(b"%PDF"):
        seal = _SEAL_LINE.search(content)
        body = content[: seal.start()] if seal else content
        return stamp_of_pdf(body), seal is not None and _sealed(seal.group(1).decode(), body)
    try:
        document = json.loads(content)
        seal = document.pop("seal", None)
        stamp = document["provenance"]
        stamp = {name: stamp[name] for name in ("digest", "built", "event_uid")}
    except (ValueError, KeyError, TypeError, AttributeError, RecursionError):
        return None, False
    return stamp, _sealed(seal, _canonical(document))


def json_report(event: TestEvent, mode: str) -> str:
    """The figures (as the API gives them) with the provenance a PDF states,
    sealed over their canonical text (``seal``)."""
    figures = event_statistics(event, mode).as_dict()
    figures["provenance"] = provenance(event, {"mode": mode}, timezone.now())
    figures["seal"] = _seal_of(_canonical(figures))
    return json.dumps(figures, indent=2, ensure_ascii=False)


def amendments_of(event: TestEvent) -> list[dict]:
    """Changes to a final event after it was finalised, oldest first.

    An entry another installation recorded (``history_source``) is that
    installation's amendment of an event it made final, named so ("name (at
    installation)"; the import refuses such entries for an event final here
    before it).  An import's own entry that leaves a row as the entry before
    it recorded it is none: it only brings what the carried history already
    lists."""
    if event.finalised is None:
        return []
    entries = changes_since(event, event.finalised)
    copies = _import_copies(entries)
    return [_described(e) for e in entries if (type(e), e.history_id) not in copies]


def _import_copies(entries: list) -> set:
    """(history model, entry id) of the import entries that change nothing."""
    by_model = defaultdict(list)
    for entry in entries:
        if entry.history_channel == "import":
            by_model[type(entry)].append(entry)
    copies = set()
    for history, imported in by_model.items():
        rows = history.objects.filter(id__in={e.id for e in imported})
        timeline = defaultdict(list)
        for entry in rows.order_by("history_date", "history_id"):
            timeline[entry.id].append(entry)
        for entry in imported:
            earlier = [e for e in timeline[entry.id] if _before(e, entry)]
            if earlier and _content(earlier[-1]) == _content(entry):
                copies.add((history, entry.history_id))
    return copies


def _before(entry, other) -> bool:
    return (entry.history_date, entry.history_id) < (other.history_date, other.history_id)


def _content(entry) -> dict:
    """A row's values in an entry, without the change stamp and file names
    (storage names differ between installations; files are not compared)."""
    return {
        f.attname: getattr(entry, f.attname)
        for f in entry.tracked_fields
        if f.name != "modified" and not isinstance(f, FileField)
    }


def changes_since(event: TestEvent, since: datetime) -> list:
    """History entries of the event's rows written after ``since``.

    The scope holds the rows there now and those the history places there
    (a row's entries keep its parent), so a row deleted since is named with
    who deleted it."""
    shifts = _ids(Shift, test_event_id=event.pk)
    legs = _ids(Leg, shift_id__in=shifts)
    segments = _ids(Segment, leg_id__in=legs)
    scope = (
        (TestEvent, {event.pk}),
        (Shift, shifts),
        (Leg, legs),
        (Segment, segments),
        (Note, _ids(Note, segment_id__in=segments)),
        (Image, _ids(Image, segment_id__in=segments)),
    )
    entries = []
    for model, ids in scope:
        entries += entries_since(model, since, id__in=ids)
    return sorted(entries, key=lambda e: e.history_date)


def _ids(model, **where) -> set[int]:
    """Ids of the rows of ``model`` that are, or once were, where ``where`` says."""
    now = model.objects.filter(**where).values_list("id", flat=True)
    once = model.history.filter(**where).values_list("id", flat=True).distinct()
    return {*now, *once}


def _described(entry) -> dict:
    return {
        "record": f"{entry.instance_type._meta.verbose_name} {entry.uid}",
        "kind": KINDS[entry.history_type],
        "kind_text": word_for(KINDS[entry.history_type]),
        "at": _text(entry.history_date),
        "by": author_of(entry),
        "channel": entry.history_channel,
        "reason": entry.history_change_reason or "",
    }


@dataclass
class Verdict:
    ok: bool
    message: str
    changes: list[dict] = field(default_factory=list)
    test_event: int | None = None

    def as_dict(self) -> dict:
        return {
            "ok": self.ok,
            "message": self.message,
            "test_event": self.test_event,
            "changes": self.changes,
        }


def verify(stamp: dict) -> Verdict:
    event = TestEvent.objects.filter(uid=stamp["event_uid"]).first()
    if event is None:
        return Verdict(
            False, _("No test event with uid %(uid)s here.") % {"uid": stamp["event_uid"]}
        )
    names = {"event": str(event)}
    digest = stamp["digest"]
    if digest == data_digest(event) or digest == data_digest(event, legacy=True):
        return Verdict(
            True, _("The data of test event '%(event)s' is unchanged.") % names, [], event.pk
        )
    built = datetime.strptime(stamp["built"], _STAMP_FORMAT).replace(tzinfo=UTC)
    changes = [_described(e) for e in changes_since(event, built)]
    message = _("The data of test event '%(event)s' changed since the report.") % names
    return Verdict(False, message, changes, event.pk)


def verify_report(content: bytes, *, kept: bool = False) -> Verdict | None:
    """Is ``content`` a report this installation made, unchanged, and does the
    database still hold the data it was built from?  None when it carries no FTT
    stamp.  ``kept``: a report file this installation stored itself, whose seal
    is not needed (those stored before reports were sealed have none).  The
    command (``ftt_report --verify``), the API and the GUI all ask here."""
    try:
        stamp, sealed = _unsealed(content)
    except TwoStamps:
        return Verdict(False, _("This file carries more than one FTT stamp; none of them counts."))
    if stamp is None:
        return None
    if not (sealed or kept):
        return Verdict(
            False,
            _(
                "This file is not a report this installation made, or it was changed "
                "after it was made: its seal does not match."
            ),
        )
    return verify(stamp)
