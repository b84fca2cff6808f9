"""Exports beside the PDF: segments as CSV, tracks as GeoJSON and GPX.

* CSV: one row per segment, masters and their reasons (children), with the
  context a spreadsheet needs (shift, leg, people, weather, notes).  Masters
  carry the distance and pose count; times are ISO 8601 in the test event's
  time zone.
* GeoJSON (RFC 7946, WGS84): one LineString feature per master segment, the
  same line its distance was measured on (joins included).
* GPX 1.1: one track per master segment with its GPS fixes and their times.

Each is made piece by piece (a line, a feature, a track; tracks read a batch of
legs at a time, POINTS_PER_BATCH), so that a download streams
(common.api.downloads) and its cost in memory does not grow with the test event.
"""

from collections import defaultdict
from collections.abc import Iterator
from xml.etree import ElementTree as ET

from django.db.models import Q, Sum

from common import geojson
from common.spreadsheet import csv_rows
from events.models import Leg, Note, Segment, TestEvent
from events.selectors.labels import segment_labels
from reports.selectors.content import reasons_by_key
from reports.selectors.statistics import event_runs
from telemetry.storage.keys import GPS_TRACK

# Segments read from the database at a time.
BATCH = 2000
# Kept GPS points whose tracks the tracks exports hold at a time.
POINTS_PER_BATCH = 100_000

CSV_COLUMNS = (
    "test_event",
    "shift",
    "leg",
    "label",
    "segment_id",
    "master_id",
    "row",
    "type",
    "start",
    "end",
    "open",
    "duration_s",
    "distance_m",
    "poses",
    "reason",
    "reason_description",
    "counts_as_intervention",
    "obstacle",
    "lighting",
    "slope",
    "weather",
    "vehicle",
    "performer",
    "test_director",
    "test_administrator",
    "robot_operator",
    "safety_officer",
    "start_longitude",
    "start_latitude",
    "start_local_x",
    "start_local_y",
    "notes",
)


def _name(person) -> str:
    return person.name if person is not None else ""


def segments_csv_rows(event: TestEvent, mode: str = GPS_TRACK) -> Iterator[str]:
    """segments.csv, a line at a time: the segments are read in batches, and a
    master's distance, pose count and end come from its stored figures (no pose is
    read)."""
    yield from csv_rows(_segment_rows(event, mode))


def _segment_rows(event: TestEvent, mode: str) -> Iterator[list]:
    tz = event.tzinfo
    runs = {run.id: run for run in event_runs(event, mode, tracks=False)}
    # The event's taxonomy: frozen for a final event (events.selectors.taxonomy).
    reasons = reasons_by_key(event)
    notes = defaultdict(list)
    for note in Note.objects.filter(segment__leg__shift__test_event=event).select_related("author"):
        notes[note.segment_id].append(
            f"{note.author.name if note.author else 'unknown'}: {note.text}"
        )
    segments = Segment.objects.filter(leg__shift__test_event=event)
    labels = segment_labels(segments)
    ordered = segments.select_related(
        "leg__weather",
        "leg__shift__vehicle",
        "leg__shift__performer",
        "leg__shift__test_director",
        "leg__shift__test_administrator",
        "leg__shift__robot_operator",
        "leg__shift__safety_officer",
    ).order_by("leg__shift__start", "leg__start", "start", "id")
    yield CSV_COLUMNS
    for seg in ordered.iterator(chunk_size=BATCH):
        run = runs.get(seg.master_id)
        shift = seg.leg.shift
        reason = reasons.get(seg.ito_reason_id) if seg.ito_reason_id else None
        end = seg.end
        if seg.parent_id is None and run is not None:
            end = run.end
        duration = (end - seg.start).total_seconds() if end else ""
        is_master = seg.parent_id is None
        yield [
            event.pk,
            shift.number,
            seg.leg.number,
            labels[seg.id],
            seg.id,
            seg.master_id,
            "master" if is_master else "reason",
            seg.segment_type_id,
            seg.start.astimezone(tz).isoformat(),
            end.astimezone(tz).isoformat() if end else "",
            "yes" if seg.end is None else "no",
            f"{duration:.3f}" if duration != "" else "",
            f"{run.distance:.3f}" if is_master and run else "",
            run.pose_count if is_master and run else "",
            seg.ito_reason_id or "",
            reason.short_description if reason else "",
            ("yes" if reason.counts_as_intervention else "no") if reason else "",
            seg.obstacle,
            seg.lighting,
            seg.slope,
            seg.leg.weather.short_description if seg.leg.weather else "",
            shift.vehicle.short_description,
            shift.performer.institution if shift.performer else "",
            _name(shift.test_director),
            _name(shift.test_administrator),
            _name(shift.robot_operator),
            _name(shift.safety_officer),
            seg.start_position.x if seg.start_position else "",
            seg.start_position.y if seg.start_position else "",
            "" if seg.start_local_x is None else seg.start_local_x,
            "" if seg.start_local_y is None else seg.start_local_y,
            " | ".join(notes.get(seg.id, [])),
        ]


def _leg_runs(event: TestEvent) -> Iterator:
    """The event's GPS runs with their tracks, a batch of legs at a time: legs of
    at most POINTS_PER_BATCH kept GPS points together (a longer leg alone), so
    that memory holds a batch's tracks and the queries do not grow per leg."""
    points = Sum(
        "segments__figures__points", filter=Q(segments__figures__mode=GPS_TRACK), default=0
    )
    legs = (
        Leg.objects.filter(shift__test_event=event)
        .order_by("shift__start", "shift_id", "start", "id")
        .annotate(points=points)
        .values_list("id", "points")
    )
    batch, held = [], 0
    for leg, count in legs:
        if batch and held + count > POINTS_PER_BATCH:
            yield from event_runs(event, GPS_TRACK, legs=batch)
            batch, held = [], 0
        batch.append(leg)
        held += count
    if batch:
        yield from event_runs(event, GPS_TRACK, legs=batch)


def track_features(event: TestEvent) -> Iterator[dict]:
    """One GeoJSON LineString feature per master segment with two positions or more."""
    tz = event.tzinfo
    for run in _leg_runs(event):
        if len(run.path_x) < 2:
            continue
        yield geojson.feature(
            geojson.line(
                [[float(x), float(y)] for x, y in zip(run.path_x, run.path_y, strict=True)]
            ),
            {
                "segment_id": run.id,
                "label": run.label,
                "type": run.kind,
                "shift_id": run.shift_id,
                "leg_id": run.leg_id,
                "start": run.start.astimezone(tz).isoformat(),
                "end": run.end.astimezone(tz).isoformat(),
                "open": run.is_open,
                "distance_m": round(run.distance, 3),
                "poses": run.pose_count,
                "reasons": sorted({s.reason for s in run.reasons}),
                "intervention": run.is_intervention,
            },
        )


def tracks_geojson_pieces(event: TestEvent) -> Iterator[str]:
    """tracks.geojson, a feature at a time."""
    return geojson.collection_chunks(track_features(event))


GPX_NS = "http://www.topografix.com/GPX/1/1"
GPX_END = "</gpx>"


def tracks_gpx_pieces(event: TestEvent) -> Iterator[str]:
    """tracks.gpx, a track at a time: the document's head, each master's track
    (the elements inherit the head's default namespace), the closing tag."""
    root = ET.Element("gpx", xmlns=GPX_NS, version="1.1", creator="FTT field test tool")
    meta = ET.SubElement(root, "metadata")
    ET.SubElement(meta, "name").text = str(event)
    head = ET.tostring(root, encoding="unicode")
    yield "<?xml version='1.0' encoding='utf-8'?>\n" + head.removesuffix(GPX_END)
    for run in _leg_runs(event):
        if run.track is None or not len(run.track):
            continue
        trk = ET.Element("trk")
        ET.SubElement(trk, "name").text = f"{run.label} ({run.kind.upper()})"
        ET.SubElement(trk, "type").text = run.kind
        seg = ET.SubElement(trk, "trkseg")
        for x, y, stamp in zip(run.track.x, run.track.y, run.track.stamps, strict=True):
            point = ET.SubElement(seg, "trkpt", lat=f"{y:.8f}", lon=f"{x:.8f}")
            ET.SubElement(point, "time").text = stamp.isoformat().replace("+00:00", "Z")
        yield ET.tostring(trk, encoding="unicode")
    yield GPX_END
