"""Exports beside the PDF: segments as CSV, tracks as GeoJSON and GPX.

* CSV: one row per segment, masters and their reasons (children), with the
  context a spreadsheet needs (shift, leg, people, weather, notes).  Masters
  carry the distance and pose count; times are ISO 8601 in the test event's
  time zone.
* GeoJSON (RFC 7946, WGS84): one LineString feature per master segment, the
  same line its distance was measured on (joins included).
* GPX 1.1: one track per master segment with its GPS fixes and their times.
"""

import io
from collections import defaultdict
from xml.etree import ElementTree as ET

from common import geojson
from common.spreadsheet import SafeWriter
from events.models import Note, Segment, TestEvent
from events.selectors.labels import segment_labels
from reports.selectors.content import reasons_by_key
from reports.selectors.statistics import event_runs
from telemetry.storage.keys import GPS_TRACK

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


def segments_csv(event: TestEvent, mode: str = GPS_TRACK) -> str:
    tz = event.tzinfo
    runs = {run.id: run for run in event_runs(event, mode)}
    # The event's taxonomy: frozen for a final event (events.selectors.taxonomy).
    reasons = reasons_by_key(event)
    notes = defaultdict(list)
    for note in Note.objects.filter(segment__leg__shift__test_event=event).select_related("author"):
        notes[note.segment_id].append(
            f"{note.author.name if note.author else 'unknown'}: {note.text}"
        )
    segments = Segment.objects.filter(leg__shift__test_event=event).select_related(
        "leg__weather",
        "leg__shift__vehicle",
        "leg__shift__performer",
        "leg__shift__test_director",
        "leg__shift__test_administrator",
        "leg__shift__robot_operator",
        "leg__shift__safety_officer",
    )
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(CSV_COLUMNS)
    ordered = sorted(segments, key=lambda s: (s.leg.shift.start, s.leg.start, s.start, s.id))
    labels = segment_labels(segments)
    for seg in ordered:
        run = runs.get(seg.master_id)
        shift = seg.leg.shift
        reason = reasons.get(seg.ito_reason_id) if seg.ito_reason_id else None
        end = seg.end
        if seg.parent_id is None and run is not None:
            end = run.end
        duration = (end - seg.start).total_seconds() if end else ""
        is_master = seg.parent_id is None
        writer.writerow(
            [
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
        )
    return out.getvalue()


def tracks_geojson(event: TestEvent) -> dict:
    tz = event.tzinfo
    features = []
    for run in event_runs(event, GPS_TRACK):
        if len(run.path_x) < 2:
            continue
        features.append(
            geojson.feature(
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
        )
    return geojson.collection(features)


def tracks_geojson_text(event: TestEvent) -> str:
    return geojson.collection_text(tracks_geojson(event)["features"])


GPX_NS = "http://www.topografix.com/GPX/1/1"


def tracks_gpx(event: TestEvent) -> str:
    ET.register_namespace("", GPX_NS)
    root = ET.Element(f"{{{GPX_NS}}}gpx", version="1.1", creator="FTT field test tool")
    meta = ET.SubElement(root, f"{{{GPX_NS}}}metadata")
    ET.SubElement(meta, f"{{{GPX_NS}}}name").text = str(event)
    for run in event_runs(event, GPS_TRACK):
        if run.track is None or not len(run.track):
            continue
        trk = ET.SubElement(root, f"{{{GPX_NS}}}trk")
        ET.SubElement(trk, f"{{{GPX_NS}}}name").text = f"{run.label} ({run.kind.upper()})"
        ET.SubElement(trk, f"{{{GPX_NS}}}type").text = run.kind
        seg = ET.SubElement(trk, f"{{{GPX_NS}}}trkseg")
        for x, y, stamp in zip(run.track.x, run.track.y, run.track.stamps, strict=True):
            point = ET.SubElement(seg, f"{{{GPX_NS}}}trkpt", lat=f"{y:.8f}", lon=f"{x:.8f}")
            ET.SubElement(point, f"{{{GPX_NS}}}time").text = stamp.isoformat().replace(
                "+00:00", "Z"
            )
    return ET.tostring(root, encoding="unicode", xml_declaration=True)
