"""The cockpit's combined reads: one request where the page needs several lists,
each exactly as the REST list of its kind shows it, in a fixed number of queries."""

from datetime import timedelta

import pytest
from django.utils import timezone

from events.models import SegmentType
from events.services import notes, segments
from telemetry.services import attachments
from tests.support.api import assert_constant_queries
from tests.support.images import png

pytestmark = pytest.mark.django_db


def results(response):
    assert response.status_code == 200, response.content
    return response.json()["results"]


def _take_overs(n, leg):
    for _ in range(n):
        segments.report_mode(leg, SegmentType.AUTO)
        segments.report_mode(leg, SegmentType.ITO)


def test_a_legs_segments_come_with_their_labels_in_one_read(api_client, leg):
    _take_overs(2, leg)
    client = api_client("viewer")
    answer = client.get(f"/gui/api/legs/{leg.pk}/segments/").json()
    listed = results(client.get(f"/api/segments/?leg={leg.pk}&page_size=5000"))
    by_id = lambda rows: {r["id"]: r for r in rows}  # noqa: E731
    assert by_id(answer["segments"]) == by_id(listed)
    assert answer["labels"] == client.get(f"/gui/api/legs/{leg.pk}/tracks/").json()["labels"]
    assert len(answer["labels"]) == len(listed) == 6


def test_the_segment_list_read_does_not_grow_with_segments(
    api_client, django_assert_max_num_queries, leg
):
    # Token + user, groups, the leg, its segments, their numbers.
    assert_constant_queries(
        api_client,
        django_assert_max_num_queries,
        f"/gui/api/legs/{leg.pk}/segments/",
        lambda n: _take_overs(n, leg),
        most=6,
    )


def _attach(n, child, tmp_path):
    master = child.parent
    for i in range(n):
        notes.add_note(child, text=f"Note {i}")
        attachments.attach_image(master, content=png(fmt="JPEG"))
        path = tmp_path / f"snap-{i}-{master.images.count()}.mcap"
        path.write_bytes(b"mcap")
        now = timezone.now()
        attachments.attach_recording(
            master, path=path, start=now - timedelta(seconds=5), end=now, topics={}
        )


def test_a_segments_notes_images_and_snapshots_come_in_one_read(
    api_client, leg, media_root, tmp_path
):
    child = segments.new_manual_segment(leg)
    segments.report_mode(leg, SegmentType.AUTO)
    other = segments.new_manual_segment(leg)  # another take-over: its files stay its own
    _attach(2, child, tmp_path)
    _attach(1, other, tmp_path)
    client = api_client("viewer")
    answer = client.get(f"/gui/api/segments/{child.pk}/attachments/").json()
    master = child.parent_id
    assert answer["master"] == master
    # A reason shows its own notes, and the images and snapshots of its master.
    assert answer["notes"] == results(client.get(f"/api/notes/?segment={child.pk}"))
    assert answer["images"] == results(client.get(f"/api/images/?segment={master}"))
    assert answer["recordings"] == results(client.get(f"/api/recordings/?segment={master}"))
    assert [n["text"] for n in answer["notes"]] == ["Note 0", "Note 1"]
    assert len(answer["images"]) == len(answer["recordings"]) == 2
    assert client.get("/gui/api/segments/999999/attachments/").status_code == 404


def test_the_attachments_read_does_not_grow_with_notes_or_files(
    api_client, django_assert_max_num_queries, leg, media_root, tmp_path
):
    child = segments.new_manual_segment(leg)
    # Token + user, groups, the segment, its notes with authors, images, snapshots.
    assert_constant_queries(
        api_client,
        django_assert_max_num_queries,
        f"/gui/api/segments/{child.pk}/attachments/",
        lambda n: _attach(n, child, tmp_path),
        most=6,
    )
