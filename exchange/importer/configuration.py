"""Importing configuration rows: reused when they match one here, else added."""

from events.models import ItoReason, Performer, Personnel, PoseSource, SegmentType, Vehicle, Weather
from exchange.importer.session import ImportSession, fold

CATALOGUES = {"weather": Weather, "segment_types": SegmentType, "ito_reasons": ItoReason}


# Archives written before vehicles had a VIN lack it; every other field is required.
_MAY_BE_MISSING = {"vin": ""}


def _field(row: dict, name: str):
    return row.get(name, _MAY_BE_MISSING[name]) if name in _MAY_BE_MISSING else row[name]


def import_catalogues(session: ImportSession):
    for table, model in CATALOGUES.items():
        known = set(model.objects.values_list("key", flat=True))
        names = {f.name for f in model._meta.concrete_fields}
        for record in session.records(table):
            if record["key"] in known:
                session.plan.note(table, "reused")
                continue
            row = model(**{k: v for k, v in record.items() if k in names})
            row.full_clean()
            row.save()
            known.add(row.key)
            session.plan.note(table, "added")


def _reuse_or_add(session: ImportSession, table, existing, make):
    if existing is not None:
        session.plan.note(table, "reused")
        return existing
    row = make()
    row.full_clean()
    row.save()
    session.plan.note(table, "added")
    return row


def import_configuration(session: ImportSession):
    """Vehicles, pose sources, performers and personnel."""
    for model, table, cache, extra in (
        (Vehicle, "vehicles", session.vehicles, ("institution", "configuration", "vin")),
        (PoseSource, "pose_sources", session.pose_sources, ()),
    ):
        for r in session.records(table):
            fields = ("key", "short_description", "long_description", *extra)
            cache[r["key"]] = _reuse_or_add(
                session,
                table,
                model.objects.filter(key=r["key"]).first(),
                lambda r=r, model=model, fields=fields: model(**{f: _field(r, f) for f in fields}),
            )
    performers = {fold(p.institution): p for p in Performer.objects.order_by("-pk")}
    for r in session.records("performers"):
        institution = _clean(r["institution"])
        row = _reuse_or_add(
            session,
            "performers",
            performers.get(fold(institution)),
            lambda institution=institution: Performer(institution=institution),
        )
        session.performers[r["institution"]] = performers[fold(institution)] = row
    people = {(fold(p.name), fold(p.institution)): p for p in Personnel.objects.order_by("-pk")}
    for r in session.records("personnel"):
        name, institution = _clean(r["name"]), _clean(r["institution"])
        match = (fold(name), fold(institution))
        row = _reuse_or_add(
            session,
            "personnel",
            people.get(match),
            lambda name=name, institution=institution: Personnel(
                name=name, institution=institution
            ),
        )
        session.people[r["ref"]] = people[match] = row


def _clean(text) -> str:
    return (text or "").strip()
