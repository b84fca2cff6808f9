"""Reports state the digest of their data and can be verified against it (issue 26)."""

import io
import json

import pytest
from django.conf import settings
from django.core.management import CommandError, call_command
from django.db import connection
from django.test.utils import CaptureQueriesContext

from events.history import authored
from events.models import ItoReason, TestEvent
from events.services import deletion, finality, logs, notes, segments
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.history_records import TRACKED
from exchange.importer import import_bundle
from reports.selectors.provenance import amendments_of, data_digest, verify
from reports.selectors.statistics import event_statistics
from telemetry.models import LocalPose, Pose
from telemetry.models.poses import FixStatus
from telemetry.services import pose_writes
from telemetry.services.pose_writes import GpsFix, MapPose
from tests.support.accounts import staff_user
from tests.support.pdf import flat, pdf_text


def _take_over(scenario):
    """The first reason (safety, counted) of the scenario's first take-over."""
    return scenario.masters["I1"].children.order_by("start", "id").first()


def _verify(path):
    out = io.StringIO()
    try:
        call_command("ftt_report", "--verify", str(path), stdout=out)
    except CommandError:
        return False, out.getvalue()
    return True, out.getvalue()


def test_pdf_verifies_until_a_reason_changes(scenario, tmp_path):
    pdf = tmp_path / "r.pdf"
    event = scenario.event
    options = ["--level", "summary", "--no-tiles", "--no-image-appendix", "-o", str(pdf)]
    call_command("ftt_report", "--test-event", str(event.pk), *options, stdout=io.StringIO())
    assert _verify(pdf) == (True, f"OK: The data of test event '{event}' is unchanged.\n")
    take_over = _take_over(scenario)
    with authored("api", user=staff_user("operator")):
        segments.annotate_segment(take_over, ito_reason="other")
    ok, said = _verify(pdf)
    assert not ok
    assert f"segment {take_over.uid}" in said and "operator-staff via api" in said


def _stamp(event, digest):
    return {"digest": digest, "built": "20260302T020000.000000Z", "event_uid": str(event.uid)}


def test_digest_reads_no_pose_and_changes_with_every_new_pose(scenario):
    event, master = scenario.event, scenario.masters["A2"]
    with CaptureQueriesContext(connection) as queries:
        digest = data_digest(event)
    pose_tables = (Pose._meta.db_table, LocalPose._meta.db_table)
    assert not [q["sql"] for q in queries if any(t in q["sql"] for t in pose_tables)]
    assert verify(_stamp(event, digest)).ok
    # A fix without a position is covered too, and so is a local pose.
    fix = GpsFix(longitude=0.0055, latitude=0.0, fix_status=FixStatus.NO_FIX)
    assert pose_writes.store_poses(master, [fix]) == 1
    after_fix = data_digest(event)
    assert after_fix != digest and not verify(_stamp(event, digest)).ok
    pose_writes.store_local_poses(master, [MapPose(x=1.0, y=2.0, frame="map")])
    assert data_digest(event) not in (digest, after_fix)
    # The same pose sent again is stored once: the digest stays.
    before_retry = data_digest(event)
    assert pose_writes.store_poses(master, [fix]) == 0
    assert data_digest(event) == before_retry


def test_a_report_of_an_earlier_version_still_verifies(scenario):
    """Its digest hashed the uids read from the poses."""
    event = scenario.event
    legacy = data_digest(event, legacy=True)
    assert legacy != data_digest(event)
    assert verify(_stamp(event, legacy)).ok
    pose_writes.store_poses(scenario.masters["A2"], [GpsFix(longitude=0.0065, latitude=0.0)])
    verdict = verify(_stamp(event, legacy))
    assert not verdict.ok and "changed since the report" in verdict.message


def test_final_report_says_final_and_lists_amendments(scenario, tmp_path):
    note = notes.add_note(_take_over(scenario), text="wet grass")
    event = finality.finalise_test_event(logs.close_test_event(scenario.event))
    administrator = staff_user("administrator")
    with authored("admin", user=administrator, reason="wrong reason tapped"):
        segments.annotate_segment(_take_over(scenario), ito_reason="other")
    with authored("gui", user=administrator, reason="note on the wrong take-over"):
        deletion.delete(note)
    assert [(a["record"], a["kind"]) for a in amendments_of(event)][1:] == [
        (f"note {note.uid}", "deleted")
    ]
    pdf = tmp_path / "final.pdf"
    options = ["--level", "summary", "--no-tiles", "--no-image-appendix", "-o", str(pdf)]
    call_command("ftt_report", "--test-event", str(event.pk), *options, stdout=io.StringIO())
    text = flat(pdf_text(pdf.read_bytes(), tmp_path))
    assert "FINAL since" in text and "amended 2 times after finalisation" in text
    assert "wrong reason tapped" in text and "frozen" in text
    assert f"note {note.uid} deleted by" in text and "(note on the wrong take-over)" in text
    assert "PROVISIONAL" not in text


@pytest.mark.django_db
def test_json_digest_is_the_same_on_another_installation(scenario, tmp_path, wipe):
    logs.close_test_event(scenario.event)
    report = tmp_path / "figures.json"
    call_command("ftt_report", "--test-event", str(scenario.event.pk), "--json", str(report))
    digest = json.loads(report.read_text())["provenance"]["digest"]
    export_events(tmp_path / "a.zip", select_events())
    wipe()
    with open_archive(tmp_path / "a.zip") as bundle:
        import_bundle(bundle)
    assert _verify(report)[0]
    assert json.loads(report.read_text())["provenance"]["digest"] == digest


@pytest.mark.django_db
def test_a_final_event_arrives_final_with_its_taxonomy_and_amendment(scenario, tmp_path, wipe):
    administrator = staff_user("administrator")
    event = logs.close_test_event(scenario.event)
    with authored("gui", user=administrator):
        event = finality.finalise_test_event(event)
    take_over = _take_over(scenario)
    with authored("admin", user=administrator, reason="wrong reason tapped"):
        segments.annotate_segment(take_over, ito_reason="other")
    report = tmp_path / "figures.json"
    call_command("ftt_report", "--test-event", str(event.pk), "--json", str(report))
    stamp = json.loads(report.read_text())["provenance"]
    figures = event_statistics(event).overall.interventions
    export_events(tmp_path / "a.zip", select_events())
    wipe()
    for model in TRACKED.values():
        model.history.all().delete()  # a base station that never saw the event
    # The catalogue here counts differently; the event keeps its frozen taxonomy.
    counted = event.taxonomy["other"]["counts"]
    ItoReason.objects.filter(key="other").update(counts_as_intervention=not counted)
    with open_archive(tmp_path / "a.zip") as bundle:
        import_bundle(bundle)

    here = TestEvent.objects.get(uid=event.uid)
    assert (here.finalised, here.finalised_by) == (event.finalised, administrator.username)
    assert here.taxonomy == event.taxonomy
    assert event_statistics(here).overall.interventions == figures
    assert [(a["record"], a["by"], a["reason"]) for a in amendments_of(here)] == [
        (
            f"segment {take_over.uid}",
            f"{administrator.username} (at {settings.FTT_INSTALLATION_NAME})",
            "wrong reason tapped",
        )
    ]
    assert _verify(report) == (True, f"OK: The data of test event '{here}' is unchanged.\n")
    again = tmp_path / "again.json"
    call_command("ftt_report", "--test-event", str(here.pk), "--json", str(again))
    there = json.loads(again.read_text())["provenance"]
    assert there["digest"] == stamp["digest"]
    assert (there["final"], there["taxonomy"]) == (stamp["final"], stamp["taxonomy"])
    assert len(there["amendments"]) == 1


def test_verify_names_a_deleted_segment_and_note_with_who_deleted_them(scenario, tmp_path):
    event = scenario.event
    take_over = _take_over(scenario)
    note = notes.add_note(take_over, text="wet grass")
    report = tmp_path / "figures.json"
    call_command("ftt_report", "--test-event", str(event.pk), "--json", str(report))
    assert _verify(report)[0]
    with authored("api", user=staff_user("administrator")):
        deletion.delete(take_over)
    ok, said = _verify(report)
    assert not ok
    assert f"segment {take_over.uid} deleted" in said
    assert f"note {note.uid} deleted" in said
    assert said.count("by administrator-staff via api") == 2
