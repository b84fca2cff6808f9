"""A test event's exports that grow with its data (segments.csv, tracks.geojson,
tracks.gpx) and a search's found segments are streamed: sent piece by piece as
they are made, with the same content the command writes; under ASGI they are
made a batch at a time, not collected whole first."""

import asyncio
import csv
import io
import json
import threading
import warnings
from xml.etree import ElementTree as ET

import httpx
import pytest
from django.core.management import call_command
from django.test import AsyncRequestFactory

from common.api import downloads
from common.api.downloads import streamed_download
from ftt_site.asgi import application
from reports.selectors import exports
from reports.selectors.exports import CSV_COLUMNS
from tests.reports.test_route_comparison import drive
from tests.support.api import streamed

GPX = {"g": "http://www.topografix.com/GPX/1/1"}


def test_the_exports_are_streamed_and_say_what_the_command_writes(scenario, api_client, tmp_path):
    files = {k: tmp_path / f"x.{k}" for k in ("csv", "geojson", "gpx")}
    options = [arg for kind, path in files.items() for arg in (f"--{kind}", str(path))]
    call_command(
        "ftt_report", "--test-event", str(scenario.event.pk), *options, stdout=io.StringIO()
    )
    client = api_client("viewer")
    base = f"/api/reports/exports/{scenario.event.pk}/"
    got = {}
    for kind, name in (
        ("csv", "segments.csv"),
        ("geojson", "tracks.geojson"),
        ("gpx", "tracks.gpx"),
    ):
        response = client.get(base + name)
        assert response.status_code == 200
        assert response["Content-Disposition"] == (
            f'attachment; filename="test-event-{scenario.event.pk}-{name}"'
        )
        got[kind] = streamed(response)
        assert got[kind] == files[kind].read_bytes()

    rows = list(csv.reader(io.StringIO(got["csv"].decode())))
    assert tuple(rows[0]) == CSV_COLUMNS
    by_kind = [row[CSV_COLUMNS.index("row")] for row in rows[1:]]
    assert (by_kind.count("master"), by_kind.count("reason")) == (7, 4)
    features = json.loads(got["geojson"])["features"]
    assert len(features) == 7
    assert {f["properties"]["segment_id"] for f in features} == {
        m.pk for m in scenario.masters.values()
    }
    tracks = ET.fromstring(got["gpx"]).findall("g:trk", GPX)
    assert len(tracks) == 6  # one master has no poses
    assert all(t.find("g:trkseg/g:trkpt/g:time", GPX) is not None for t in tracks)


def test_a_streamed_download_is_made_in_batches_on_the_request_thread_under_asgi(monkeypatch):
    monkeypatch.setattr(downloads, "PIECES_PER_BATCH", 10)
    made, threads = [], set()

    def pieces():
        for n in range(35):
            made.append(n)
            threads.add(threading.get_ident())
            yield f"{n}\n"

    request = AsyncRequestFactory().get("/api/reports/exports/1/segments.csv")
    response = streamed_download(request, pieces(), "text/csv", "segments.csv")

    async def read():
        chunks = []
        async for chunk in response:
            chunks.append((chunk, len(made)))
        return chunks

    with warnings.catch_warnings():
        # Django warns when it must collect a plain iterator whole for ASGI.
        warnings.simplefilter("error")
        chunks = asyncio.run(read())
    assert [made_when_sent for _, made_when_sent in chunks] == [10, 20, 30, 35]
    assert b"".join(chunk for chunk, _ in chunks) == "".join(f"{n}\n" for n in range(35)).encode()
    assert len(threads) == 1
    assert response["Content-Disposition"] == 'attachment; filename="segments.csv"'


@pytest.mark.django_db(transaction=True)
def test_the_production_server_streams_an_export_that_reads_the_database(api_client, shift):
    """Through the ASGI application: the pieces read the database on the request's
    thread, and Django does not collect them whole first."""
    legs = [drive(shift, [(7.1 + i * 1e-5, 50.6 + n * 1e-4) for i in range(30)]) for n in range(3)]
    token = api_client("viewer").token

    async def get(name):
        transport = httpx.ASGITransport(app=application)
        async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as client:
            url = f"/api/reports/exports/{shift.test_event_id}/{name}"
            return await client.get(url, headers={"Authorization": f"Token {token}"})

    with warnings.catch_warnings():
        warnings.filterwarnings("error", message="StreamingHttpResponse must consume")
        sheet, tracks = asyncio.run(get("segments.csv")), asyncio.run(get("tracks.geojson"))
    assert sheet.status_code == tracks.status_code == 200
    rows = list(csv.DictReader(io.StringIO(sheet.text)))
    assert sorted(int(r["leg"]) for r in rows) == sorted(leg.number for leg in legs)
    assert {int(r["poses"]) for r in rows} == {30}
    features = json.loads(tracks.text)["features"]
    assert sorted(f["properties"]["leg_id"] for f in features) == sorted(leg.pk for leg in legs)


def test_the_tracks_exports_hold_a_batch_of_legs_at_a_time(shift, monkeypatch):
    for n in range(3):
        drive(shift, [(7.1 + i * 1e-5, 50.6 + n * 1e-4) for i in range(30)])
    event = shift.test_event
    whole = "".join(exports.tracks_geojson_pieces(event))
    batches = []
    read = exports.event_runs
    monkeypatch.setattr(exports, "POINTS_PER_BATCH", 40)
    monkeypatch.setattr(
        exports,
        "event_runs",
        lambda *a, legs, **k: batches.append(legs) or read(*a, legs=legs, **k),
    )
    assert "".join(exports.tracks_geojson_pieces(event)) == whole
    assert [len(legs) for legs in batches] == [1, 1, 1]
    assert len(json.loads(whole)["features"]) == 3
