"""Importing the change history of the archived records (exchange.history_records).

An entry is added only if this installation has no entry of the same record
with the same time and kind, so importing an archive again adds nothing.  The
entries are written as they are (not through simple-history's signals, which
would stamp them as made now by the import), marked as the archive's
installation's record (``history_source``), their author a name, never an
account here.  An entry is skipped, and counted, when its row is not one the
archive carries (an archive speaks only of its own rows), when it is dated
after the import (beyond FTT_IMPORT_CLOCK_TOLERANCE), or when it is dated
after the finalisation of a test event final here before the import.  The import's own
entries, made while it adds or changes rows, stay beside them.
"""

import uuid
from collections import defaultdict
from datetime import timedelta

from django.conf import settings
from django.utils import timezone
from django.utils.translation import gettext

from events.models import Personnel, TestCase
from events.models.changes import CHANNELS
from exchange import records as rec
from exchange.history_records import TRACKED, reference_field, value_fields, value_in
from exchange.importer.plan import MalformedRecord
from exchange.importer.session import ImportSession, fold

KINDS = ("+", "~", "-")
# The way from a tracked row to its test event.
EVENT_PATHS = {
    "test_event": "",
    "shift": "test_event__",
    "leg": "shift__test_event__",
    "segment": "leg__shift__test_event__",
    "note": "segment__leg__shift__test_event__",
    "image": "segment__leg__shift__test_event__",
}
# The archive table of each tracked record kind's rows.
TABLES = {
    "test_event": "test_events",
    "shift": "shifts",
    "leg": "legs",
    "segment": "segments",
    "note": "notes",
    "image": "images",
}
_CHANNELS = {key for key, _label in CHANNELS}


def import_history(session: ImportSession):
    by_model = defaultdict(list)
    for r in session.records("history"):
        if r.get("model") not in TRACKED:
            # An entry of a record kind a newer FTT tracks: not kept here.
            continue
        if r.get("type") not in KINDS or r.get("channel") not in _CHANNELS:
            raise MalformedRecord(
                gettext("%(where)s: unknown kind or channel of a history entry.")
                % {"where": session.where}
            )
        by_model[r["model"]].append(r)
    for name, records in by_model.items():
        _import_entries(session, name, records)


def _carried(session: ImportSession, name: str) -> set:
    uids = set()
    for uid in session.carried[TABLES[name]]:
        try:
            uids.add(uuid.UUID(uid))
        except ValueError:
            continue
    return uids


def _final_here(session: ImportSession, name: str, model, ids) -> dict:
    """Row id: when its test event became final here, for the events final
    before this import (not those the archive makes final)."""
    path = EVENT_PATHS[name]
    rows = model.objects.filter(pk__in=ids, **{f"{path}finalised__isnull": False})
    rows = rows.exclude(**{f"{path}pk__in": session.arriving})
    return dict(rows.values_list("pk", f"{path}finalised"))


def _import_entries(session: ImportSession, name: str, records: list):
    model = TRACKED[name]
    history = model.history.model
    carried = _carried(session, name)
    latest = timezone.now() + timedelta(seconds=settings.FTT_IMPORT_CLOCK_TOLERANCE)
    uids = {uuid.UUID(r["uid"]) for r in records} & carried
    ids = dict(model.objects.filter(uid__in=uids).values_list("uid", "pk"))
    stored = history.objects.filter(id__in=ids.values())
    known = set(stored.values_list("id", "history_date", "history_type"))
    final = _final_here(session, name, model, ids.values())
    fields = value_fields(model)
    references = _References(session, fields, records)
    added = []
    for r in records:
        session.where = gettext("history record of %(table)s %(uid)s") % {
            "table": name,
            "uid": r["uid"],
        }
        at = rec.time_in(r["at"], "at")
        if at is None:
            raise MalformedRecord(gettext("%(where)s: it has no time.") % {"where": session.where})
        if uuid.UUID(r["uid"]) not in carried:
            session.plan.note("history", "refused")
            continue
        if at > latest:
            session.plan.note("history", "refused")
            continue
        pk = ids[uuid.UUID(r["uid"])]
        if pk in final and at > final[pk] and (pk, at, r["type"]) not in known:
            # Only an amendment made here changes what is final here.
            session.plan.note("history", "refused")
            continue
        if (pk, at, r["type"]) in known:
            session.plan.note("history", "unchanged")
            continue
        values = r["values"]
        if not isinstance(values, dict):
            raise MalformedRecord(
                gettext("%(where)s: its values are not an object.") % {"where": session.where}
            )
        entry = history(
            id=pk,
            history_date=at,
            history_type=r["type"],
            history_channel=r["channel"],
            history_author=str(r.get("author") or "")[:150],
            history_source=str(r.get("installation") or session.source)[:150],
            history_change_reason=r.get("reason") or None,
        )
        for field in fields:
            if field.name not in values:
                # Written before the field existed.
                setattr(entry, field.attname, field.get_default())
            elif field.is_relation:
                setattr(entry, field.attname, references.resolve(field, values[field.name]))
            else:
                value = value_in(field, values[field.name], field.name)
                setattr(entry, field.attname, value)
        known.add((pk, at, r["type"]))
        added.append(entry)
    history.objects.bulk_create(added, batch_size=1000)
    session.plan.note("history", "added", len(added))


class _References:
    """The ids here of the rows the entries refer to, looked up once per model."""

    def __init__(self, session: ImportSession, fields, records):
        self.session = session
        self.ids: dict = {}
        wanted = defaultdict(set)
        for field in fields:
            if field.is_relation:
                for r in records:
                    value = r["values"].get(field.name) if isinstance(r["values"], dict) else None
                    if value is not None:
                        wanted[field.related_model].add(_hashable(value))
        for model, refs in wanted.items():
            self.ids[model] = self._look_up(model, refs)

    def _look_up(self, model, refs) -> dict:
        if model is Personnel:
            return {ref: self.session.people[ref].pk for ref in refs if ref in self.session.people}
        if model is TestCase:
            pairs = model.objects.filter(key__in={key for _event, key in refs})
            found = pairs.values_list("test_event__uid", "key", "pk")
            return {(str(event), key): pk for event, key, pk in found}
        field = reference_field(model)
        if field == "institution":
            folded = {fold(ref): ref for ref in refs}
            return {
                folded[fold(row.institution)]: row.pk
                for row in model.objects.all()
                if fold(row.institution) in folded
            }
        if field == "uid":
            found = model.objects.filter(uid__in={uuid.UUID(ref) for ref in refs})
            return {str(uid): pk for uid, pk in found.values_list("uid", "pk")}
        return dict(model.objects.filter(key__in=refs).values_list("key", "pk"))

    def resolve(self, field, value):
        """The id here of the row ``value`` names, or None where it is not here."""
        if value is None:
            return None
        return self.ids[field.related_model].get(_hashable(value))


def _hashable(value):
    if isinstance(value, list):
        return tuple(str(v) for v in value)
    if not isinstance(value, str):
        raise MalformedRecord(
            gettext("%(value)s is not a reference to a row.") % {"value": repr(value)}
        )
    return value
