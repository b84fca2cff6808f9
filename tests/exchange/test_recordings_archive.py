"""Black-box snapshots travel in archives, file and all."""

from datetime import timedelta

import pytest

from events.models import Segment
from exchange.archive import open_archive
from exchange.export import export_events, select_events
from exchange.importer import import_bundle
from telemetry.models import Recording
from telemetry.services.attachments import attach_recording
from tests.support.field_day import field_day
from tests.support.mcap_files import read_mcap, write_fixes

pytestmark = pytest.mark.django_db(transaction=False)


def load(path):
    with open_archive(path) as bundle:
        return import_bundle(bundle)


def test_a_snapshot_is_exported_and_imported_with_its_file(media_root, tmp_path, wipe):
    field_day()
    ito = Segment.objects.filter(segment_type_id="ito", parent=None).first()
    source = tmp_path / "snapshot-a.mcap"
    topics = write_fixes(source, [7.0, 8.0])
    stored = attach_recording(
        ito, path=source, start=ito.start - timedelta(seconds=20), end=ito.start, topics=topics
    )
    export_events(tmp_path / "day.zip", select_events())
    wipe()
    assert not Recording.objects.exists()

    plan = load(tmp_path / "day.zip")
    assert plan.counts["recordings"]["added"] == 1
    back = Recording.objects.get(uid=stored.uid)
    assert back.segment.uid == ito.uid
    assert (back.start, back.end, back.topics) == (stored.start, stored.end, topics)
    assert [m.latitude for _, _, m in read_mcap(back.file.path)["messages"]] == [7.0, 8.0]
    assert load(tmp_path / "day.zip").counts["recordings"]["unchanged"] == 1
