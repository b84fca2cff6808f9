"""Robot-data lists and tracks run a fixed number of queries, however many rows."""

import pytest

from events.models import SegmentType
from events.services import segments
from telemetry.services import recording
from telemetry.services.recording import GpsFix, MapPose
from tests.events.api.querycount import LIST_QUERIES, assert_constant_queries
from tests.telemetry.api.conftest import png


def _poses(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    recording.record_poses(master, [GpsFix(7 + i / 1000, 50.0) for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _local_poses(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    recording.record_local_poses(master, [MapPose(i, 0.0, "map") for i in range(n)])
    segments.report_mode(leg, SegmentType.ITO)


def _maps(n, leg):
    for _ in range(n):
        recording.record_map(
            leg.shift,
            png=png(colour=(len(leg.shift.maps.all()), 0, 0)),
            frame="map",
            width=4,
            height=3,
            resolution=0.05,
            origin_x=0,
            origin_y=0,
        )


def _images(n, leg):
    master = segments.report_mode(leg, SegmentType.AUTO).master
    for _ in range(n):
        recording.attach_image(master, content=png(fmt="JPEG"), filename="x.jpg")


CASES = {
    "/api/poses/": (_poses, LIST_QUERIES),
    "/api/local-poses/": (_local_poses, LIST_QUERIES),
    "/api/maps/": (_maps, LIST_QUERIES),
    "/api/images/": (_images, LIST_QUERIES),
    # Token + user, groups, the leg, its masters, their points: more segments add none.
    "/api/tracks/?leg={leg}": (_poses, 5),
    "/api/local-tracks/?leg={leg}": (_local_poses, 5),
    "/api/tracks/?shift={shift}": (_poses, 5),
    "/api/tracks/?test_event={test_event}": (_poses, 5),
    "/api/local-tracks/?shift={shift}": (_local_poses, 5),
}


@pytest.mark.parametrize("url", CASES)
def test_list_queries_do_not_grow_with_rows(
    url, api_client, django_assert_max_num_queries, leg, media_root
):
    add, most = CASES[url]
    assert_constant_queries(
        api_client,
        django_assert_max_num_queries,
        url.format(leg=leg.pk, shift=leg.shift_id, test_event=leg.shift.test_event_id),
        lambda n: add(n, leg),
        most=most,
    )
