"""Importing test plans: test cases with their criteria, a leg's test case, and
the judgements people recorded.

A test case is named by its test event and key.  One that exists here is kept
as it is (the plan is written on one installation); one that does not is added
with its criteria.  A judgement is added where this installation has none for
that criterion and leg, and otherwise the later one wins.
"""

from django.contrib.gis.geos import LineString, MultiPolygon, Polygon
from django.utils.translation import gettext as _

from events.models import Criterion, ItoReason, Judgement, Leg, Shift, TestCase, TestEvent
from events.services import plans
from exchange import records as rec
from exchange.importer.session import ImportSession


def _line_in(coords, field: str):
    if coords is None:
        return None
    try:
        return LineString([tuple(point) for point in coords], srid=4326)
    except (TypeError, ValueError, IndexError):
        raise rec.RecordError(
            _("%(field)s: %(value)s is not a line.") % {"field": field, "value": f"{coords!r}"}
        ) from None


def _area_in(coords, field: str):
    if coords is None:
        return None
    try:
        polygons = [Polygon(*[[tuple(p) for p in ring] for ring in rings]) for rings in coords]
        return MultiPolygon(*polygons, srid=4326)
    except (TypeError, ValueError, IndexError):
        raise rec.RecordError(
            _("%(field)s: %(value)s is not a list of polygons.")
            % {"field": field, "value": f"{coords!r}"}
        ) from None


def import_test_cases(session: ImportSession):
    for r in session.records("test_cases"):
        session.where = f"test_cases record {r['key']}"
        event_id = session.entry_id(session.events, TestEvent, r["test_event"], "test event")
        if TestCase.objects.filter(test_event_id=event_id, key=r["key"]).exists():
            session.plan.note("test_cases", "reused")
            continue
        case = TestCase(
            test_event_id=event_id,
            key=r["key"],
            title=r["title"],
            description=r.get("description", ""),
            area=_area_in(r.get("area"), "area"),
            route=_line_in(r.get("route"), "route"),
            planned_runs=r["planned_runs"],
        )
        case.full_clean(validate_unique=False)
        case.save()
        for c in r["criteria"]:
            criterion = Criterion(
                test_case=case, kind=c["kind"], value=c.get("value"), text=c.get("text", "")
            )
            reasons = list(ItoReason.objects.filter(pk__in=c.get("reasons", [])))
            if len(reasons) != len(set(c.get("reasons", []))):
                session.refuse(f"{session.where}: a criterion names an unknown ITO reason.")
            # The rules of a criterion made in admin (events.models.plans).
            criterion.full_clean()
            Criterion.check_reasons(criterion.kind, reasons)
            criterion.save()
            criterion.reasons.set(reasons)
        session.plan.note("test_cases", "added")
        session.changed.append(case)


def test_case_id(session: ImportSession, shift_id: int, key) -> int | None:
    """The id here of the test case ``key`` of the shift's test event."""
    if key is None:
        return None
    event_id = Shift.objects.filter(pk=shift_id).values_list("test_event_id", flat=True).get()
    case = TestCase.objects.filter(test_event_id=event_id, key=key).first()
    if case is None:
        session.refuse(
            f"{session.where}: its test case '{key}' is neither in the archive nor here."
        )
    return case.pk


def import_judgements(session: ImportSession):
    for r in session.records("judgements"):
        session.where = f"judgements record {r['test_case']}"
        event_id = session.entry_id(session.events, TestEvent, r["test_event"], "test event")
        case = TestCase.objects.filter(test_event_id=event_id, key=r["test_case"]).first()
        wanted = r["criterion"]
        criterion = next(
            (
                c
                for c in (case.criteria.all() if case else ())
                if (c.kind, c.value, c.text) == (wanted["kind"], wanted["value"], wanted["text"])
            ),
            None,
        )
        if criterion is None:
            session.refuse(f"{session.where}: its criterion is neither in the archive nor here.")
        leg = None
        if r["leg"] is not None:
            leg = Leg.objects.get(pk=session.entry_id(session.legs, Leg, r["leg"], "leg"))
        at = rec.time_in(r["at"], "at")
        row = Judgement.objects.filter(criterion=criterion, leg=leg).first()
        if row is not None and (at <= row.at or (row.passed, row.note) == (r["passed"], r["note"])):
            session.plan.note("judgements", "unchanged")
            continue
        # Through the service: the same rules as a judgement made here.
        made = plans.judge(criterion, passed=r["passed"], leg=leg, note=r["note"])
        Judgement.objects.filter(pk=made.pk).update(at=at)
        session.plan.note("judgements", "added" if row is None else "updated")
