"""The report's segment page names each black-box snapshot of the segment."""

from events.services import logs
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from telemetry.services import attachments
from tests.support.mcap_files import write_fixes
from tests.support.pdf import flat, pdf_text
from tests.support.scenario import T0, _at, _switch


def test_the_segment_page_names_the_snapshot_its_window_and_topics(
    vehicle, performer, media_root, tmp_path
):
    event = logs.create_test_event(location="Feld", time_zone="UTC", at=T0)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    leg = logs.create_leg(shift=shift, at=T0)
    _switch(leg, "auto", T0, 0, 0.000)
    ito = _switch(leg, "ito", T0, 100, 0.003)
    _switch(leg, "auto", T0, 130, 0.004)
    path = tmp_path / "snapshot-take-over.mcap"
    topics = write_fixes(path, [1.0, 2.0])
    attachments.attach_recording(ito, path=path, start=_at(T0, 80), end=_at(T0, 110), topics=topics)
    logs.close_test_event(event, at=_at(T0, 200))

    text = flat(pdf_text(render_report(event, ReportOptions(no_tiles=True)).pdf, tmp_path))
    start, end = _at(T0, 80).strftime("%H:%M:%S"), _at(T0, 110).strftime("%H:%M:%S")
    assert "snapshot-take-over.mcap (30 s, 2 messages" in text
    # The window wraps in the narrow table cell: check its two ends.
    assert f"/gps_fix), {start}–" in text and end in text
    event.language = "de"
    event.save(update_fields=["language"])
    german = flat(pdf_text(render_report(event, ReportOptions(no_tiles=True)).pdf, tmp_path))
    assert "snapshot-take-over.mcap (30 s, 2 Nachrichten, 0,0 MB; /gps_fix)" in german
