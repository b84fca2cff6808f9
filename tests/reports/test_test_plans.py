"""Did we do what the test plan said: verdicts of test cases from the statistics'
own figures, per leg and per case, in the API, the CSV and the JSON export."""

import csv
import io
from datetime import timedelta

import pytest
from pyproj import Geod

from common import roles
from events.models import Criterion, ItoReason, SegmentType, TestCase
from events.services import logs, segments
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from telemetry.services import pose_writes
from tests.support.pdf import flat, pdf_text, save_pages

Kind = Criterion.Kind
STEP = 2.8e-5  # about 2 m of longitude at 50.6° north


def line(n, lat=50.6):
    return [(7.1 + i * STEP, lat) for i in range(n)]


def length(points) -> float:
    lons, lats = zip(*points, strict=True)
    return Geod(ellps="WGS84").line_length(lons, lats)


def drive(leg, mode, points=(), reason=None):
    master = segments.report_mode(leg, mode).master
    if points:
        fixes = [
            pose_writes.GpsFix(lon, lat, robot_stamp=master.start + timedelta(milliseconds=i))
            for i, (lon, lat) in enumerate(points)
        ]
        pose_writes.store_poses(master, fixes)
    if reason:
        segments.annotate_segment(master.children.get(), ito_reason=reason)
    return master


def case(event, key, runs=1, **criteria):
    made = TestCase.objects.create(test_event=event, key=key, title=key.title(), planned_runs=runs)
    for kind, value in criteria.items():
        c = Criterion.objects.create(test_case=made, kind=kind, value=value)
        if kind == Kind.FORBIDDEN_REASONS:
            c.value = None
            c.save()
            c.reasons.set([ItoReason.objects.get(key="safety")])
    return made


@pytest.fixture
def plan(shift):
    event = shift.test_event
    loop_a, loop_b, loop_c = line(51), line(31, 50.601), line(21, 50.602)
    gravel = case(
        event,
        "gravel",
        runs=2,
        **{Kind.DISTANCE_WITHOUT_INTERVENTION: round(length(loop_a)) - 1, Kind.RUNS_COMPLETED: 2},
    )
    night = case(
        event,
        "night",
        **{Kind.INTERVENTIONS_PER_KM: 5.0, Kind.FORBIDDEN_REASONS: 0},
    )
    person = case(event, "person")
    judged = Criterion.objects.create(
        test_case=person, kind=Kind.JUDGED, text="Gate passed cleanly"
    )

    first = logs.create_leg(shift=shift, test_case=gravel)
    drive(first, SegmentType.AUTO, loop_a)
    drive(first, SegmentType.ITO, reason="safety")
    drive(first, SegmentType.AUTO, loop_b)
    second = logs.create_leg(shift=shift, test_case=gravel)  # closes the first
    drive(second, SegmentType.AUTO, loop_c)
    third = logs.create_leg(shift=shift, test_case=night)
    drive(third, SegmentType.AUTO, loop_a)
    drive(third, SegmentType.ITO, reason="safety")
    drive(third, SegmentType.AUTO, loop_a)
    fourth = logs.create_leg(shift=shift, test_case=person)
    drive(fourth, SegmentType.AUTO, loop_c)
    unplanned = logs.create_leg(shift=shift)  # closes the fourth
    return {
        "event": event,
        "legs": (first, second, third, fourth, unplanned),
        "judged": judged,
        "loops": (length(loop_a), length(loop_b), length(loop_c)),
    }


def verdicts_of(result, key):
    found = next(c for c in result["cases"] if c["key"] == key)
    return found, {v["kind"]: v for v in found["verdicts"]}


def by_leg(case):
    return {leg["leg"]: {v["kind"]: v for v in leg["verdicts"]} for leg in case["legs"]}


def test_verdicts_follow_the_statistics_rules(api_client, plan):
    client = api_client(roles.VIEWER)
    event, (first, second, third, fourth, unplanned) = plan["event"], plan["legs"]
    a, b, c = plan["loops"]
    result = client.get(f"/api/reports/test-plan/{event.pk}/").json()
    assert result["unplanned_legs"] == [unplanned.pk]

    gravel, own = verdicts_of(result, "gravel")
    # Just met: the longest stretch without intervention is loop a (b follows the take-over).
    distance = own[Kind.DISTANCE_WITHOUT_INTERVENTION]
    assert distance["measured"] == pytest.approx(a, abs=0.01) and distance["verdict"] == "pass"
    legs = by_leg(gravel)
    assert legs[first.pk][Kind.DISTANCE_WITHOUT_INTERVENTION]["verdict"] == "pass"
    # The second run ended short of it.
    second_run = legs[second.pk][Kind.DISTANCE_WITHOUT_INTERVENTION]
    assert second_run["measured"] == pytest.approx(c, abs=0.01)
    assert second_run["verdict"] == "fail"
    assert (
        own[Kind.RUNS_COMPLETED] | {"measured": 2.0, "verdict": "pass"} == own[Kind.RUNS_COMPLETED]
    )
    assert gravel["verdict"] == "pass"
    assert gravel["progress"].startswith("run 2 of 2 · ")

    night, own = verdicts_of(result, "night")
    # One intervention over two loops of a: just above the 5.0 per km allowed.
    per_km = 1 / (2 * a / 1000)
    assert 5.0 < per_km < 5.1
    assert own[Kind.INTERVENTIONS_PER_KM]["measured"] == pytest.approx(per_km, rel=1e-6)
    assert own[Kind.INTERVENTIONS_PER_KM]["verdict"] == "fail"
    assert own[Kind.FORBIDDEN_REASONS]["measured"] == ["safety"]
    assert own[Kind.FORBIDDEN_REASONS]["verdict"] == "fail"
    assert by_leg(night)[third.pk][Kind.INTERVENTIONS_PER_KM]["verdict"] == "fail"
    assert night["verdict"] == "fail"

    person, own = verdicts_of(result, "person")
    assert own[Kind.JUDGED]["verdict"] == "needs a judgement"
    assert by_leg(person)[fourth.pk][Kind.JUDGED]["verdict"] == "needs a judgement"
    assert person["verdict"] == "needs a judgement"


def test_an_open_run_is_not_yet_judged_until_it_reaches_the_distance(api_client, shift):
    event = shift.test_event
    gravel = case(event, "gravel", runs=3, **{Kind.DISTANCE_WITHOUT_INTERVENTION: 50})
    leg = logs.create_leg(shift=shift, test_case=gravel)
    master = drive(leg, SegmentType.AUTO, line(11))
    client = api_client(roles.VIEWER)

    def state():
        result = client.get(f"/api/reports/test-plan/{event.pk}/").json()
        found, own = verdicts_of(result, "gravel")
        return found["progress"], own[Kind.DISTANCE_WITHOUT_INTERVENTION]["verdict"]

    progress, verdict = state()
    assert verdict == "not yet"
    assert progress == f"run 1 of 3 · {length(line(11)):.0f} m of 50 m without intervention"
    more = [(7.1 + i * STEP, 50.6) for i in range(11, 31)]
    pose_writes.store_poses(
        master,
        [
            pose_writes.GpsFix(lon, lat, robot_stamp=master.start + timedelta(seconds=1 + i))
            for i, (lon, lat) in enumerate(more)
        ],
    )
    progress, verdict = state()
    assert verdict == "pass" and f"{length(line(31)):.0f} m of 50 m" in progress


def test_a_person_judges_and_exports_agree(api_client, plan):
    event, judged = plan["event"], plan["judged"]
    operator = api_client(roles.OPERATOR)
    answer = operator.post(
        "/api/reports/judgements/", {"criterion": judged.pk, "passed": True, "note": "clean"}
    )
    assert answer.status_code == 201, answer.content
    measured = operator.post(
        "/api/reports/judgements/",
        {"criterion": Criterion.objects.exclude(kind=Kind.JUDGED).first().pk, "passed": True},
    )
    assert measured.status_code == 400 and "measured" in measured.json()["errors"]["criterion"][0]
    viewer = api_client(roles.VIEWER)
    refused = viewer.post("/api/reports/judgements/", {"criterion": judged.pk, "passed": False})
    assert refused.status_code == 403

    result = viewer.get(f"/api/reports/test-plan/{event.pk}/").json()
    person, own = verdicts_of(result, "person")
    assert own[Kind.JUDGED]["verdict"] == "pass" and own[Kind.JUDGED]["note"] == "clean"
    assert person["verdict"] == "pass"

    as_json = viewer.get(f"/api/reports/exports/{event.pk}/test-plan.json").json()
    assert as_json == result
    sheet = viewer.get(f"/api/reports/exports/{event.pk}/test-plan.csv").content.decode()
    rows = list(csv.DictReader(io.StringIO(sheet)))
    expected = [(c["key"], v["verdict"]) for c in result["cases"] for v in c["verdicts"]] + [
        (c["key"], v["verdict"])
        for c in result["cases"]
        for leg in c["legs"]
        for v in leg["verdicts"]
    ]
    assert sorted((r["test_case"], r["verdict"]) for r in rows) == sorted(expected)
    night = [r for r in rows if r["test_case"] == "night" and r["scope"] == "case"]
    assert {r["verdict"] for r in night} == {"fail"}


def test_a_leg_takes_only_a_test_case_of_its_own_test_event(api_client, shift):
    elsewhere = logs.create_test_event(location="elsewhere")
    foreign = case(elsewhere, "foreign")
    response = api_client(roles.OPERATOR).post(
        "/api/legs/", {"shift": shift.pk, "test_case": foreign.pk}
    )
    assert response.status_code == 400
    assert "another test event" in response.json()["errors"]["test_case"][0]
    own = case(shift.test_event, "own")
    response = api_client(roles.OPERATOR).post(
        "/api/legs/", {"shift": shift.pk, "test_case": own.pk}
    )
    assert response.status_code == 201 and response.json()["test_case"] == own.pk


def test_the_report_has_a_test_plan_section(plan, tile_server, tmp_path, settings):
    settings.FTT_TILE_CACHE = tmp_path / "tiles"
    result = render_report(plan["event"], ReportOptions(level="summary", tile_url=tile_server.url))
    save_pages(result.pdf, "test-plan", dpi=90)
    text = flat(pdf_text(result.pdf, tmp_path, layout=False))
    assert "Test plan" in text
    assert "gravel: Gravel" in text and "night: Night" in text
    assert "interventions per km ≤ 5" in text
    assert "needs a judgement" in text
    fifth = plan["legs"][4]
    assert f"Legs outside the plan: Shift {fifth.shift.number} · Leg {fifth.number}" in text
