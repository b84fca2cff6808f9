"""The report check over the API: the answer of ``ftt_report --verify`` (issue 26)."""

import io
import json
import re
import uuid

from django.core.files.base import ContentFile
from django.core.files.uploadedfile import SimpleUploadedFile
from django.core.management import call_command

from reports.models import Report
from tests.support.pdf import flat, pdf_text

OPTIONS = ["--level", "summary", "--no-tiles", "--no-image-appendix"]


def _take_over(scenario):
    return scenario.masters["I1"].children.order_by("start", "id").first()


def _upload(client, name: str, content: bytes):
    upload = SimpleUploadedFile(name, content)
    return client.post("/api/reports/verify/", {"file": upload}, format="multipart")


def _pdf(event, tmp_path) -> bytes:
    pdf = tmp_path / "r.pdf"
    call_command(
        "ftt_report", "--test-event", str(event.pk), *OPTIONS, "-o", str(pdf), stdout=io.StringIO()
    )
    return pdf.read_bytes()


def test_an_uploaded_pdf_is_ok_until_a_reason_changes_then_names_who(
    scenario, api_client, tmp_path
):
    event = scenario.event
    pdf = _pdf(event, tmp_path)
    assert "Provenance" in flat(pdf_text(pdf, tmp_path))
    viewer = api_client("viewer")
    answer = _upload(viewer, "r.pdf", pdf)
    assert answer.status_code == 200
    assert answer.json() == {
        "ok": True,
        "message": f"The data of test event '{event}' is unchanged.",
        "test_event": event.pk,
        "changes": [],
    }
    take_over = _take_over(scenario)
    operator = api_client("operator")
    changed = operator.patch(
        f"/api/segments/{take_over.pk}/", {"ito_reason": "other"}, format="json"
    )
    assert changed.status_code == 200
    answer = _upload(viewer, "r.pdf", pdf).json()
    assert answer["ok"] is False
    assert answer["message"] == f"The data of test event '{event}' changed since the report."
    assert [(c["record"], c["by"], c["channel"]) for c in answer["changes"]] == [
        (f"segment {take_over.uid}", operator.user.username, "api")
    ]


def test_a_json_report_and_a_stored_report_are_checked_too(scenario, api_client, tmp_path):
    event = scenario.event
    figures = tmp_path / "figures.json"
    call_command("ftt_report", "--test-event", str(event.pk), "--json", str(figures))
    viewer = api_client("viewer")
    assert _upload(viewer, "figures.json", figures.read_bytes()).json()["ok"] is True
    stored = Report.objects.create(
        test_event=event, status=Report.Status.DONE, pdf=ContentFile(_pdf(event, tmp_path), "r.pdf")
    )
    answer = viewer.get(f"/api/reports/{stored.pk}/verify/")
    assert answer.status_code == 200 and answer.json()["ok"] is True


def test_a_file_without_a_stamp_or_no_file_is_refused_with_a_field_message(scenario, api_client):
    viewer = api_client("viewer")
    answer = _upload(viewer, "notes.txt", b"just some text")
    assert answer.status_code == 400
    assert "no FTT data digest" in answer.json()["errors"]["file"][0]
    empty = viewer.post("/api/reports/verify/", {}, format="multipart")
    assert empty.status_code == 400
    assert empty.json()["errors"]["file"] == ["Choose a report file (PDF or JSON) to check."]
    assert api_client(anonymous=True).post("/api/reports/verify/", {}).status_code in (401, 403)


def test_amendments_count_what_was_changed_after_finalising(scenario, api_client):
    from events.history import authored
    from events.services import finality, logs
    from events.services import segments as segment_services
    from tests.support.accounts import staff_user

    event = scenario.event
    viewer = api_client("viewer")
    url = f"/api/reports/amendments/{event.pk}/"
    assert viewer.get(url).json() == {
        "final": False,
        "finalised": None,
        "count": 0,
        "amendments": [],
    }
    event = finality.finalise_test_event(logs.close_test_event(event))
    assert viewer.get(url).json()["count"] == 0
    admin = staff_user("administrator")
    for reason, value in (("mis-tapped", "other"), ("checked the video", "safety")):
        with authored("admin", user=admin, reason=reason):
            segment_services.annotate_segment(_take_over(scenario), ito_reason=value)
    answer = viewer.get(url).json()
    assert answer["final"] is True and answer["count"] == 2
    assert [(a["by"], a["channel"], a["reason"]) for a in answer["amendments"]] == [
        (admin.username, "admin", "mis-tapped"),
        (admin.username, "admin", "checked the video"),
    ]
    assert viewer.get("/api/reports/amendments/999999/").status_code == 404


def test_a_json_file_nested_too_deeply_is_refused_with_a_field_message(db, api_client):
    answer = _upload(api_client("viewer"), "deep.json", b"[" * 100_000 + b"]" * 100_000)
    assert answer.status_code == 400
    assert "no FTT data digest" in answer.json()["errors"]["file"][0]


def test_a_copied_stamp_a_second_stamp_or_an_edited_report_does_not_verify(
    scenario, api_client, tmp_path
):
    event = scenario.event
    pdf = _pdf(event, tmp_path)
    viewer = api_client("viewer")
    assert _upload(viewer, "r.pdf", pdf).json()["ok"] is True
    stamp = re.search(rb"ftt-digest-sha256-\S{64}.*?ftt-event-[0-9a-f-]{36}", pdf, re.S)
    copied = b"%PDF-1.7\nA letter that says all is well.\n" + stamp.group(0)
    edited = pdf.replace(b"Provenance", b"Provenanze", 1)
    figures = tmp_path / "figures.json"
    call_command("ftt_report", "--test-event", str(event.pk), "--json", str(figures))
    document = json.loads(figures.read_text())
    assert _upload(viewer, "figures.json", figures.read_bytes()).json()["ok"] is True
    document["statistics" if "statistics" in document else next(iter(document))] = "better"
    forged_json = json.dumps(document).encode()
    for name, content in (
        ("copied.pdf", copied),
        ("edited.pdf", edited),
        ("forged.json", forged_json),
    ):
        answer = _upload(viewer, name, content)
        assert answer.status_code == 200, (name, answer.content)
        assert answer.json()["ok"] is False, name
        assert "seal does not match" in answer.json()["message"], name
    other = pdf.replace(str(event.uid).encode(), str(uuid.uuid4()).encode(), 1)
    answer = _upload(viewer, "two.pdf", other).json()
    assert answer["ok"] is False and "more than one FTT stamp" in answer["message"]


def test_a_text_file_holding_a_report_s_stamp_and_seal_is_no_report(scenario, api_client, tmp_path):
    pdf = _pdf(scenario.event, tmp_path)
    viewer = api_client("viewer")
    stamp = re.search(rb"ftt-digest-sha256-\S{64}.*?ftt-event-[0-9a-f-]{36}", pdf, re.S)
    seal = pdf[pdf.rindex(b"\n%ftt-seal-") :]
    for copied in (b"All is well.\n" + stamp.group(0), b"All is well.\n" + stamp.group(0) + seal):
        answer = _upload(viewer, "letter.txt", copied)
        assert answer.status_code == 400, answer.content
        assert "no FTT data digest" in answer.json()["errors"]["file"][0]
