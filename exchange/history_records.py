"""The change history of archived records (archive table ``history``).

One row per history entry (django-simple-history) of an archived test event,
shift, leg, segment, note or image: the record (``model``, ``uid``), when
(``at``), what kind (``type``: + ~ -), through what (``channel``), who
(``author``: the account's name, as accounts are not carried; an importing
installation keeps it as a name, never as an account), where (``installation``:
for an entry imported from a third installation, that one; none means the
installation named in the manifest), why (``reason``), and the record's values
after the change.  The values refer to
other rows the way exchange.records does (uids, keys, institutions, person
refs); a row that no longer exists is referred to as null.

An entry is the same on every installation by its record's uid, its time and
its kind: an import adds only the entries it does not have.
"""

import uuid
from collections import defaultdict
from datetime import datetime

from django.contrib.gis.geos import GEOSGeometry
from django.db.models import FileField, ForeignKey
from django.db.models.fields.files import FieldFile
from django.utils.translation import gettext as _

from events.models import Leg, Note, Performer, Personnel, Segment, Shift, TestCase, TestEvent
from exchange import records as rec
from telemetry.models import Image

# The archive's name of each tracked record kind.
TRACKED = {
    "test_event": TestEvent,
    "shift": Shift,
    "leg": Leg,
    "segment": Segment,
    "note": Note,
    "image": Image,
}
# simple-history's own columns and the row's id here: not part of the values.
_OWN = {"id", "history_id", "history_date", "history_type", "history_user"}
_OWN |= {"history_channel", "history_author", "history_source", "history_change_reason"}


def value_fields(model) -> list:
    """The fields of ``model``'s history entries that hold the record's values."""
    return [f for f in model.history.model._meta.fields if f.name not in _OWN]


def reference_field(model) -> str | None:
    """What another installation knows a row of ``model`` by (None: a person's ref)."""
    if model is Personnel:
        return None
    if model is Performer:
        return "institution"
    if model is TestCase:
        return "key"
    names = {f.name for f in model._meta.fields}
    return "uid" if "uid" in names else "key"


class HistoryExport:
    """The history entries of the archived records; ``ids`` maps an archive name
    of :data:`TRACKED` to the ids of its archived rows."""

    def __init__(self, ids: dict[str, list[int]], since: datetime | None = None):
        self.entries: list[tuple[str, object]] = []
        for name, model in TRACKED.items():
            rows = model.history.filter(id__in=ids.get(name, ()))
            if since is not None:
                rows = rows.filter(history_date__gte=since)
            rows = rows.select_related("history_user").order_by("history_date", "history_id")
            self.entries += [(name, entry) for entry in rows]
        self.referred: dict = defaultdict(set)  # model: ids the entries refer to
        for name, entry in self.entries:
            for field in value_fields(TRACKED[name]):
                value = getattr(entry, field.attname)
                if isinstance(field, ForeignKey) and value is not None:
                    self.referred[field.related_model].add(value)
        self._refs: dict = {}

    def ids_of(self, model) -> set:
        return self.referred.get(model, set())

    def _reference(self, model, pk):
        if model not in self._refs:
            found = model.objects.filter(pk__in=self.referred[model])
            if model is Personnel:
                self._refs[model] = {p.pk: rec.person_ref(p) for p in found.only("pk")}
            elif model is TestCase:
                self._refs[model] = {
                    pk: [str(uid), key]
                    for pk, uid, key in found.values_list("pk", "test_event__uid", "key")
                }
            else:
                field = reference_field(model)
                self._refs[model] = {pk: str(v) for pk, v in found.values_list("pk", field)}
        return self._refs[model].get(pk)

    def records(self):
        for name, entry in self.entries:
            values = {}
            for field in value_fields(TRACKED[name]):
                value = getattr(entry, field.attname)
                if isinstance(field, ForeignKey):
                    if value is not None:
                        value = self._reference(field.related_model, value)
                    values[field.name] = value
                else:
                    values[field.name] = value_out(value)
            user = entry.history_user
            yield {
                "model": name,
                "uid": str(entry.uid),
                "at": rec.time_out(entry.history_date),
                "type": entry.history_type,
                "channel": entry.history_channel,
                "author": user.get_username() if user is not None else entry.history_author,
                # Where an imported entry was recorded; none: here.
                "installation": entry.history_source or None,
                "reason": entry.history_change_reason or "",
                "values": values,
            }


def value_out(value):
    if isinstance(value, datetime):
        return rec.time_out(value)
    if isinstance(value, GEOSGeometry):
        return rec.point_out(value)
    if isinstance(value, uuid.UUID):
        return str(value)
    if isinstance(value, FieldFile):
        return value.name
    return value


def value_in(field, value, where: str):
    """A stored value from an archived one (references are resolved by the importer)."""
    if value is None:
        return None
    if field.get_internal_type() == "DateTimeField":
        return rec.time_in(value, where)
    if field.get_internal_type() == "PointField":
        return rec.point_in(value, where)
    if field.get_internal_type() == "UUIDField":
        return uuid.UUID(value)
    if isinstance(field, FileField) and not isinstance(value, str):
        raise rec.RecordError(
            _("%(field)s: %(value)s is not a file name.") % {"field": where, "value": f"{value!r}"}
        )
    return value
