"""What an archive carries besides the log: the change history, the robot's reason
suggestions, start uncertainties and missed fixes, the test plan; and that an
archive of an older FTT without them still imports."""

import io
import json
from datetime import timedelta

import pytest
from django.conf import settings
from django.contrib.auth import get_user_model
from django.contrib.gis.geos import LineString, MultiPolygon, Polygon
from django.core.management import CommandError, call_command
from django.urls import reverse
from django.utils import timezone

from events.models import (
    Criterion,
    ItoReason,
    Judgement,
    Leg,
    Note,
    Personnel,
    Segment,
    Shift,
    TestCase,
    TestEvent,
    Vehicle,
)
from events.selectors.history import history_of
from events.services import finality, logs, plans, segments
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import ImportRefused, import_bundle
from reports.selectors.provenance import amendments_of
from telemetry.models import Image
from tests.support.archives import members_of, replace_record, signed_archive
from tests.support.jobs import run_queued_jobs

pytestmark = pytest.mark.django_db

TRACKED = (TestEvent, Shift, Leg, Segment, Note, Image, Personnel, Vehicle, ItoReason)


def load(path):
    with open_archive(path) as bundle:
        return import_bundle(bundle)


def export(path):
    export_events(path, select_events())
    return path


@pytest.fixture
def base_station(wipe):
    """Forget everything including the history and the accounts, as on another machine."""

    def _wipe():
        wipe()
        for model in TRACKED:
            model.history.all().delete()
        get_user_model().objects.all().delete()

    return _wipe


@pytest.fixture
def take_over(leg):
    return segments.report_mode(
        leg, "ito", suggested_reason="safety", start_uncertainty=1.25
    ).master.children.get()


def _history(api_client, segment) -> list:
    client = api_client("viewer")
    answer = client.get(reverse("segment-history", args=[segment.pk]))
    assert answer.status_code == 200
    return answer.json()


def test_api_change_reaches_the_base_station_with_author_channel_and_values(
    take_over, api_client, tmp_path, media_root, base_station
):
    operator = api_client("operator")
    url = reverse("segment-detail", args=[take_over.pk])
    assert operator.patch(url, {"ito_reason": "planner"}, format="json").status_code == 200
    logs.close_test_event(take_over.leg.shift.test_event)
    archive = export(tmp_path / "robot.zip")
    name = operator.user.username
    base_station()

    plan = load(archive)
    here = Segment.objects.get(uid=take_over.uid)
    shown = _history(api_client, here)
    api = [e for e in shown if e["channel"] == "api"]
    assert len(api) == 1 and api[0]["kind"] == "changed"
    # The robot's account is a name recorded there, not an account here.
    assert api[0]["author"] == f"{name} (at {settings.FTT_INSTALLATION_NAME})"
    assert api[0]["imported_from"] == settings.FTT_INSTALLATION_NAME
    moved = [(c["field"], c["before"], c["after"]) for c in api[0]["changes"]]
    assert ("ito_reason", "unassigned", "planner") in moved
    imported = [e for e in shown if e["channel"] == "import"]
    assert [e["kind"] for e in imported] == ["created"]
    assert shown[0] == imported[0]  # the import came last
    assert plan.counts["history"]["added"] > 0

    again = load(archive)
    assert again.counts["history"] == {"unchanged": plan.counts["history"]["added"]}
    assert again.changes() == 0
    assert _history(api_client, here) == shown


def test_robot_suggestion_start_uncertainty_missed_fixes_and_regulator_fields_travel(
    take_over, tmp_path, media_root, base_station
):
    leg = take_over.leg
    regulator = {"initiator": "autonomous_system", "severity": "critical", "location_type": "yard"}
    segments.annotate_segment(take_over, **regulator)
    logs.count_missed_fixes(leg.pk, 3)
    morning = export(tmp_path / "morning.zip")
    logs.count_missed_fixes(leg.pk, 4)
    evening = export(tmp_path / "evening.zip")
    master = take_over.parent
    base_station()

    load(morning)
    assert Leg.objects.get(uid=leg.uid).fixes_missed == 3
    load(evening)
    load(morning)  # a stale archive counts fewer, which undoes nothing
    assert Leg.objects.get(uid=leg.uid).fixes_missed == 7
    child = Segment.objects.get(uid=take_over.uid)
    assert (child.suggested_reason_id, child.ito_reason_id) == ("safety", "unassigned")
    assert child.start_uncertainty == 1.25
    assert {name: getattr(child, name) for name in regulator} == regulator
    assert Segment.objects.get(uid=master.uid).start_uncertainty == 1.25


def _as_older_ftt(path, tmp_path):
    """The archive as an FTT before these fields wrote it: no history, no new fields."""
    members = members_of(path.read_bytes())
    del members["data/history.jsonl"]
    for table, names in (
        ("test_events", ("finalised", "finalised_by", "taxonomy")),
        ("legs", ("fixes_missed",)),
        ("segments", ("suggested_reason", "start_uncertainty")),
    ):
        members = replace_record(
            members, table, lambda r, names=names: {k: v for k, v in r.items() if k not in names}
        )
    older = tmp_path / "older.zip"
    older.write_bytes(signed_archive(members))
    return older


def test_an_archive_without_history_and_new_fields_still_imports(
    take_over, tmp_path, media_root, base_station
):
    logs.count_missed_fixes(take_over.leg_id, 2)
    segments.annotate_segment(take_over, ito_reason="planner")
    older = _as_older_ftt(export(tmp_path / "robot.zip"), tmp_path)
    assert "suggested_reason" not in members_of(older.read_bytes())["data/segments.jsonl"].decode()
    base_station()

    plan = load(older)
    assert "history" not in plan.counts
    child = Segment.objects.get(uid=take_over.uid)
    assert (child.ito_reason_id, child.suggested_reason_id, child.start_uncertainty) == (
        "planner",
        None,
        None,
    )
    assert Leg.objects.get().fixes_missed == 0
    assert {e.history_channel for e in child.history.all()} == {"import"}


def test_finalisation_travels_and_an_older_archive_never_undoes_it(
    take_over, tmp_path, media_root, base_station
):
    event = logs.close_test_event(take_over.leg.shift.test_event)
    closed = export(tmp_path / "closed.zip")
    event = finality.finalise_test_event(event)
    final = export(tmp_path / "final.zip")
    base_station()

    load(closed)
    assert TestEvent.objects.get(uid=event.uid).finalised is None
    load(final)
    load(closed)  # older, not final yet: the event stays final
    here = TestEvent.objects.get(uid=event.uid)
    assert (here.finalised, here.taxonomy) == (event.finalised, event.taxonomy)


def test_a_final_event_meeting_the_same_event_reopened_here_is_refused(
    take_over, tmp_path, media_root, base_station
):
    event = logs.close_test_event(take_over.leg.shift.test_event)
    closed = export(tmp_path / "closed.zip")
    finality.finalise_test_event(event)
    final = export(tmp_path / "final.zip")
    base_station()
    load(closed)
    logs.reopen_test_event(TestEvent.objects.get(uid=event.uid))

    with pytest.raises(ImportRefused, match="final in the archive but open here"):
        load(final)
    assert TestEvent.objects.get(uid=event.uid).finalised is None


def test_history_names_rows_by_what_every_installation_knows(take_over, tmp_path, media_root):
    segments.annotate_segment(take_over, ito_reason="planner")
    members = members_of(export(tmp_path / "robot.zip").read_bytes())
    entries = [json.loads(line) for line in members["data/history.jsonl"].splitlines()]
    mine = [e for e in entries if e["uid"] == str(take_over.uid)]
    assert [e["values"]["ito_reason"] for e in mine] == ["unassigned", "planner"]
    assert {e["values"]["leg"] for e in mine} == {str(take_over.leg.uid)}
    assert {e["values"]["parent"] for e in mine} == {str(take_over.parent.uid)}
    shifts = [e for e in entries if e["model"] == "shift"]
    assert shifts and {e["values"]["vehicle"] for e in shifts} == {take_over.leg.shift.vehicle.key}
    listed = {json.loads(line)["ref"] for line in members["data/personnel.jsonl"].splitlines()}
    named = {e["values"][role] for e in shifts for role in ("test_director", "robot_operator")}
    assert named - {None} and named - {None} <= listed
    assert all("id" not in e["values"] for e in entries)


def _criteria(case) -> list:
    return [
        (c.kind, c.value, c.text, sorted(r.pk for r in c.reasons.all()))
        for c in case.criteria.all()
    ]


def _plan_of(event) -> list:
    return [
        (
            case.key,
            case.title,
            case.planned_runs,
            case.route.coords,
            case.area.coords,
            _criteria(case),
            sorted(
                (j.criterion.text, str(j.leg.uid) if j.leg else "", j.passed, j.note, j.at)
                for j in Judgement.objects.filter(criterion__test_case=case)
            ),
            sorted(str(leg.uid) for leg in case.legs.all()),
        )
        for case in event.test_cases.order_by("key")
    ]


def test_test_plan_judgements_and_leg_links_travel(shift, tmp_path, media_root, base_station):
    case = TestCase.objects.create(
        test_event=shift.test_event,
        key="gravel",
        title="Gravel loop",
        planned_runs=2,
        route=LineString((7.1000001, 50.7), (7.2, 50.7100002), srid=4326),
        area=MultiPolygon(Polygon(((7, 50), (7.3, 50), (7.3, 50.8), (7, 50))), srid=4326),
    )
    Criterion.objects.create(test_case=case, kind="forbidden_reasons").reasons.set(["safety"])
    judged = Criterion.objects.create(test_case=case, kind="judged", text="Gate passed cleanly")
    leg = logs.create_leg(shift=shift, test_case=case)
    plans.judge(judged, passed=True, leg=leg, note="clean")
    plans.judge(judged, passed=False, note="not overall")
    morning = export(tmp_path / "morning.zip")
    plans.judge(judged, passed=False, leg=leg, note="touched the gate")
    evening = export(tmp_path / "evening.zip")
    expected = _plan_of(shift.test_event)
    base_station()

    load(morning)
    load(evening)
    stale = load(morning)
    assert stale.changes() == 0 and stale.counts["test_cases"] == {"reused": 1}
    assert _plan_of(TestEvent.objects.get()) == expected
    assert Leg.objects.get(uid=leg.uid).test_case.key == "gravel"


def _entries(path) -> list[dict]:
    members = members_of(path.read_bytes())
    return [json.loads(line) for line in members["data/history.jsonl"].splitlines()]


def _with_entries(path, entries: list[dict], tmp_path, name: str):
    members = members_of(path.read_bytes())
    body = "".join(json.dumps(e) + "\n" for e in entries).encode()
    crafted = tmp_path / name
    crafted.write_bytes(signed_archive({**members, "data/history.jsonl": body}))
    return crafted


def test_imported_history_never_lands_on_rows_outside_the_archive_nor_in_the_future(
    take_over, tmp_path, media_root, base_station
):
    mine = take_over.leg.shift.test_event
    other = logs.create_test_event(location="Bonn", version="1.0", time_zone="Europe/Berlin")
    everything = export(tmp_path / "all.zip")
    one = tmp_path / "one.zip"
    export_events(one, select_events([str(mine.uid)]))
    base_station()
    load(everything)
    here = TestEvent.objects.get(uid=other.uid)
    before = here.history.count()

    entries = _entries(one)
    event_entry = next(e for e in entries if e["uid"] == str(mine.uid))
    onto_other = {**event_entry, "uid": str(other.uid), "at": "2020-01-01T00:00:00+00:00"}
    onto_other["values"] = {**event_entry["values"], "location": "forged"}
    segment_entry = next(e for e in entries if e["uid"] == str(take_over.uid))
    future = {**segment_entry, "at": (timezone.now() + timedelta(days=1)).isoformat()}
    plan = load(_with_entries(one, [*entries, onto_other, future], tmp_path, "crafted.zip"))

    assert here.history.count() == before
    assert not here.history.filter(location="forged").exists()
    segment = Segment.objects.get(uid=take_over.uid)
    assert not segment.history.filter(history_date__gt=timezone.now()).exists()
    assert plan.counts["history"]["refused"] == 2
    assert any("refused" in line for line in plan.lines())


def test_a_forged_author_is_a_name_from_elsewhere_and_no_amendment_here(
    take_over, tmp_path, media_root, base_station, role_user
):
    event = finality.finalise_test_event(logs.close_test_event(take_over.leg.shift.test_event))
    final = export(tmp_path / "final.zip")
    base_station()
    load(final)
    admin = role_user("administrator")
    entries = _entries(final)
    last = [e for e in entries if e["uid"] == str(take_over.uid)][-1]
    forged = {**last, "channel": "admin", "author": admin.username}
    before = {**forged, "at": (event.finalised - timedelta(seconds=1)).isoformat()}
    after = {**forged, "at": (event.finalised + timedelta(seconds=1)).isoformat()}
    plan = load(_with_entries(final, [*entries, before, after], tmp_path, "forged.zip"))

    assert plan.counts["history"]["refused"] == 1  # the one after the finalisation
    segment = Segment.objects.get(uid=take_over.uid)
    shown = [e for e in history_of(segment) if e["channel"] == "admin"]
    assert len(shown) == 1
    assert shown[0]["author"] != admin.username and admin.username in shown[0]["author"]
    assert shown[0]["imported_from"]
    assert not segment.history.filter(history_user=admin).exists()
    assert amendments_of(TestEvent.objects.get(uid=event.uid)) == []


def test_the_import_s_own_changes_name_the_administrator_who_imported(
    take_over, tmp_path, media_root, base_station, api_client
):
    archive = export(tmp_path / "robot.zip")
    base_station()
    admin = api_client("administrator")
    answer = admin.post(
        "/api/archives/import/", {"archive": archive.open("rb")}, format="multipart"
    )
    assert answer.status_code in (200, 202)
    assert run_queued_jobs() == 1

    segment = Segment.objects.get(uid=take_over.uid)
    own = [e for e in history_of(segment) if e["channel"] == "import"]
    assert own and {e["author"] for e in own} == {admin.user.username}
    assert {e["imported_from"] for e in own} == {None}


def test_ftt_import_by_an_administrator_amends_a_final_event_naming_them(
    take_over, tmp_path, media_root, base_station, role_user
):
    event = finality.finalise_test_event(logs.close_test_event(take_over.leg.shift.test_event))
    final = export(tmp_path / "final.zip")
    base_station()
    load(final)
    changed = tmp_path / "changed.zip"
    members = replace_record(
        members_of(final.read_bytes()),
        "segments",
        lambda r: (
            {**r, "ito_reason": "planner", "annotated": timezone.now().isoformat()}
            if r["uid"] == str(take_over.uid)
            else r
        ),
    )
    changed.write_bytes(signed_archive(members))
    with pytest.raises(CommandError, match="no active administrator"):
        call_command("ftt_import", str(changed), by="nobody", stdout=io.StringIO())
    with pytest.raises(CommandError, match="final"):
        call_command("ftt_import", str(changed), stdout=io.StringIO())
    admin = role_user("administrator")

    call_command("ftt_import", str(changed), by=admin.username, stdout=io.StringIO())

    assert Segment.objects.get(uid=take_over.uid).ito_reason_id == "planner"
    listed = amendments_of(TestEvent.objects.get(uid=event.uid))
    assert listed and {(a["by"], a["channel"]) for a in listed} == {(admin.username, "import")}
    assert {a["reason"] for a in listed} == {"archive import"}
