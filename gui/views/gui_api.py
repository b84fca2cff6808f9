"""Read-only JSON the GUI needs beyond the REST API: tracks of a leg drawn in
one request, and the local map with its placement on the GPS map.

Same authentication, roles and error shape as /api/ (DRF views with the
project defaults); the numbers come from selectors, never from here.
"""

import threading

import numpy as np
from django.db import DatabaseError, connections
from django.shortcuts import get_object_or_404
from django.utils.decorators import method_decorator
from django.utils.translation import gettext as _
from django.views.decorators.gzip import gzip_page
from drf_spectacular.utils import extend_schema
from rest_framework import serializers
from rest_framework.exceptions import ValidationError
from rest_framework.response import Response
from rest_framework.views import APIView

from basemaps.selectors.layers import layer_list
from common import roles
from events import feed
from events.api import serializers as s
from events.api.serializers import (
    NoteSerializer,
    SegmentSerializer,
    open_take_over_ids,
    touched_rows,
)
from events.models import Leg, Note, Segment, SegmentType, Shift, Vehicle
from events.selectors.cases import test_case_areas, test_case_routes
from events.selectors.labels import label, leg_numbers, short_label
from events.services import segments as rules
from gui.forms import gui_forms
from rosbridge_app.models import Collector
from rosbridge_app.selectors.collectors import collector_status, collectors
from rosbridge_app.selectors.control import logging_control, snapshot_control, stores_nothing
from rosbridge_app.selectors.ending import ACTIONS, ending
from rosbridge_app.selectors.fleet import fleet
from rosbridge_app.selectors.parameter_editor import parameter_rows
from rosbridge_app.services.collectors import issue_command
from telemetry.api.serializers import ImageSerializer, RecordingSerializer
from telemetry.models import Image, Recording
from telemetry.selectors import tracks
from telemetry.selectors.cached_tracks import cached_tracks, caches_any
from telemetry.selectors.distances import displayed_distances
from telemetry.selectors.maps import current_map
from telemetry.selectors.overlay import map_corners, overlay
from telemetry.selectors.track_drawing import (
    MAX_ZOOM,
    MIN_LOCAL_ZOOM,
    drawn,
    fit_zoom,
    thinned,
    tolerance,
)
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK


@extend_schema(exclude=True)
class GuiView(APIView):
    """Internal to the GUI pages, so kept out of the documented /api/ schema."""


class TrackQuery(serializers.Serializer):
    """What part of a leg's tracks the map asks for, and how finely (docs/gui.md, Big tracks)."""

    zoom = serializers.IntegerField(required=False, min_value=MIN_LOCAL_ZOOM, max_value=MAX_ZOOM)
    local_zoom = serializers.IntegerField(
        required=False, min_value=MIN_LOCAL_ZOOM, max_value=MAX_ZOOM
    )
    fit = serializers.CharField(required=False)
    map = serializers.ChoiceField(choices=[GPS_TRACK, LOCAL_TRACK], required=False)
    bbox = serializers.CharField(required=False)
    bbox_zoom = serializers.IntegerField(
        required=False, min_value=MIN_LOCAL_ZOOM, max_value=MAX_ZOOM
    )

    def validate_fit(self, value):
        parts = value.split(",")
        if len(parts) != 2 or not all(p.isdigit() and 0 < int(p) <= 20000 for p in parts):
            raise serializers.ValidationError(_("Give the map's size in pixels as width,height."))
        return tuple(int(p) for p in parts)

    def validate_bbox(self, value):
        try:
            box = tuple(float(p) for p in value.split(","))
        except ValueError:
            box = ()
        if len(box) != 4 or not all(np.isfinite(box)) or box[0] > box[2] or box[1] > box[3]:
            raise serializers.ValidationError(_("Give the area in view as xmin,ymin,xmax,ymax."))
        return box

    def validate(self, attrs):
        # Only the local map zooms below 0: ``zoom`` is the GPS map's unless map=local.
        for name in () if attrs.get("map") == LOCAL_TRACK else ("zoom", "bbox_zoom"):
            if attrs.get(name, 0) < 0:
                message = _("Give a zoom level from 0 to %(max)s.") % {"max": MAX_ZOOM}
                raise serializers.ValidationError({name: message})
        detail = ("map", "bbox", "bbox_zoom")
        missing = [name for name in detail if name not in attrs]
        if missing and len(missing) < len(detail):
            raise serializers.ValidationError(
                {missing[0]: _("The area in view needs map, bbox and bbox_zoom together.")}
            )
        return attrs


# A leg's tracks are megabytes of repetitive digits; gzip shrinks them about
# threefold.  They hold no secret next to user input, so BREACH does not apply.
@method_decorator(gzip_page, name="dispatch")
class LegTracks(GuiView):
    """Every master segment's GPS and local track, with its driven distance, and
    every segment's label ("Leg 2 · #7"), so the page names segments as the report does.

    ``?zoom=Z`` / ``?local_zoom=Z`` thin each track to what that zoom of its map
    can show, ``?fit=W,H`` to what a map of that size shows of the whole leg;
    ``?map=gps&bbox=...&bbox_zoom=Z`` answers one map's tracks only, finer in the
    area in view (see docs/gui.md).  Distances are always those of the full tracks."""

    def get(self, request, pk):
        leg = get_object_or_404(Leg, pk=pk)
        query = TrackQuery(data=request.query_params)
        query.is_valid(raise_exception=True)
        q = query.validated_data
        masters = list(tracks.masters(leg=leg.pk))
        if "map" in q:
            return Response(_in_view(leg, masters, q))
        loaded = cached_tracks(masters)
        gps, local = loaded[GPS_TRACK], loaded[LOCAL_TRACK]
        zooms = {GPS_TRACK: q.get("zoom"), LOCAL_TRACK: q.get("local_zoom")}
        for mode, loaded in ((GPS_TRACK, gps), (LOCAL_TRACK, local)):
            if zooms[mode] is None and "fit" in q:
                zooms[mode] = fit_zoom(mode, list(loaded.values()), *q["fit"])
        distances = displayed_distances(masters)
        segments = {}
        for master in masters:
            segment_id, mode = master.pk, master.segment_type_id
            g, lo = gps.get(segment_id), local.get(segment_id)
            segments[segment_id] = {
                "mode": mode,
                "ito": mode == SegmentType.ITO,
                # [lat, lon]: the order Leaflet takes.
                "gps": [] if g is None else _drawn(g, GPS_TRACK, zooms[GPS_TRACK]),
                "local": [] if lo is None else _drawn(lo, LOCAL_TRACK, zooms[LOCAL_TRACK]),
                "distance_m": distances[segment_id],
                # Where a take-over circle goes when the master has a start position.
                "start": _lat_lon(master.start_position),
                "start_local": None
                if master.start_local_x is None or master.start_local_y is None
                else [master.start_local_x, master.start_local_y],
            }
        body = {"leg": leg.pk, "segments": segments, **leg_labels(leg)}
        body.update(zoom=zooms[GPS_TRACK], local_zoom=zooms[LOCAL_TRACK])
        if zooms[GPS_TRACK] is not None:
            body["tolerance_deg"] = tolerance(GPS_TRACK, zooms[GPS_TRACK])
        return Response(body)


class LegDistances(GuiView):
    """Every master segment's driven distance, as LegTracks answers it, without
    the points: the cockpit reads it after each live batch of positions, which it
    draws itself, so a long leg does not cross the wire for a few numbers."""

    def get(self, request, pk):
        leg = get_object_or_404(Leg, pk=pk)
        masters = list(tracks.masters(leg=leg.pk))
        distances = displayed_distances(masters)
        return Response({"leg": leg.pk, "distances": {m.pk: distances[m.pk] for m in masters}})


def read_ahead(leg: Leg) -> threading.Thread | None:
    """Starts reading what LegTracks answers from (the cached tracks of both maps)
    in a thread of its own, and returns the thread.

    The cockpit's page calls it for the leg it opens: its scripts ask for the
    tracks about half a second after the page, and a process that has not cached
    them yet (the first visit after a restart) reads them meanwhile instead of
    after the request (``cached_tracks`` lets the request wait for this read).
    Where the process keeps any of them it starts nothing (None): the request
    then reads only what changed, and a thread with a connection and a second
    count of the poses would only load the machine while the page starts."""
    masters = list(tracks.masters(leg=leg.pk))
    if not masters or caches_any(masters):
        return None
    thread = threading.Thread(target=_read_leg, args=(masters,), name="tracks-read-ahead")
    thread.daemon = True
    thread.start()
    return thread


def _read_leg(masters: list[Segment]) -> None:
    try:
        cached_tracks(masters)
    except DatabaseError:
        # Only a head start: the tracks request reads whatever is not cached yet.
        pass
    finally:
        # This thread's own connection; the thread ends here.
        connections.close_all()


def _lat_lon(point) -> list[float] | None:
    return None if point is None else [point.y, point.x]


def _in_view(leg, masters, q) -> dict:
    """One map's tracks, at ``bbox_zoom`` in the area in view and at ``zoom`` (or
    in full without it) elsewhere; segments without points are left out."""
    mode = q["map"]
    box = q["bbox"]
    segments = {}
    for segment_id, track in cached_tracks(masters, [mode])[mode].items():
        if len(track):
            segments[segment_id] = _drawn(track, mode, q.get("zoom"), box, q["bbox_zoom"])
    return {
        "leg": leg.pk,
        "map": mode,
        "zoom": q.get("zoom"),
        "bbox_zoom": q["bbox_zoom"],
        "segments": segments,
    }


def _drawn(track, mode, zoom, box=None, box_zoom=None) -> list[list[float]]:
    outside = 0.0 if zoom is None else tolerance(mode, zoom)
    inside = 0.0 if box_zoom is None else tolerance(mode, box_zoom)
    if box is None:
        x, y = thinned(track, outside)
    else:
        x, y = drawn(track.x, track.y, outside, box, inside)
    # 1e-7 degrees is 1 cm; the 17 digits a float prints would triple the bytes.
    # GPS points go as [lat, lon], the order Leaflet takes.
    pairs = np.column_stack([y, x] if mode == GPS_TRACK else [x, y])
    return np.round(pairs, 7).tolist()


def leg_labels(leg: Leg) -> dict[str, dict[int, str]]:
    """Every segment's label ("Leg 2 · #7") and short label ("#7"), as the page shows them."""
    numbers = leg_numbers(leg.pk).items()
    return {
        "labels": {pk: label(leg.number, n) for pk, n in numbers},
        "short_labels": {pk: short_label(n) for pk, n in numbers},
    }


class LegSegments(GuiView):
    """The leg's segments as ``/api/segments/?leg=`` lists them, with their labels:
    one request where the page needs both to draw its list."""

    def get(self, request, pk):
        return Response(leg_segments(get_object_or_404(Leg, pk=pk)))


def leg_segments(leg: Leg) -> dict:
    """``last_event``: the change feed's newest id before the rows were read, so the
    page tells this answer from a state it kept later (static/gui/lastknown.js)."""
    last_event = feed.newest()
    rows = SegmentSerializer(Segment.objects.filter(leg=leg), many=True).data
    return {
        "leg": leg.pk,
        "last_event": last_event,
        "segments": rows,
        **leg_labels(leg),
        "open_take_over": open_take_over_ids([leg.pk])[leg.pk],
    }


class SegmentWrite(GuiView):
    """A segment write by the segment rules (events.services.segments), answered with
    the row it wrote and every row that change touched, with their labels, so the page
    redraws them without reading the list again:
    ``{"segment": row, "segments": [rows], "labels": {id: label}, "short_labels": {...},
    "open_take_over": id or None}``."""

    write_role = roles.OPERATOR
    answer_status = 200

    def write(self, request, pk) -> Segment:
        raise NotImplementedError

    def post(self, request, pk):
        row = self.write(request, pk)
        # A new reason under a new master: the master's change closed the previous
        # master, the reason's closed its sibling; each id brings what it touched.
        rows, labels, short_labels, take_over = {}, {}, {}, None
        for changed in touched_rows({row.pk, row.parent_id} - {None}).values():
            rows.update((r["id"], r) for r in changed["segments"])
            labels.update(changed["labels"])
            short_labels.update(changed["short_labels"])
            take_over = changed["open_take_over"]
        body = {
            "segment": SegmentSerializer(row).data,
            "segments": list(rows.values()),
            "labels": labels,
            "short_labels": short_labels,
            "open_take_over": take_over,
        }
        return Response(body, status=self.answer_status)


def checked(serializer_class, request):
    serializer = serializer_class(data=request.data, context={"request": request})
    serializer.is_valid(raise_exception=True)
    return serializer


class ManualSegment(SegmentWrite):
    """An operator records a take-over (``legs/{id}/manual-segment/`` of the API)."""

    answer_status = 201

    def write(self, request, pk):
        leg = get_object_or_404(Leg, pk=pk)
        payload = checked(s.ManualSegmentSerializer, request)
        reason = s.reason_key(payload.validated_data)
        uid = payload.validated_data.get("uid")
        at = payload.recorded_at()
        return rules.new_manual_segment(leg, reason=reason, uid=uid, at=at, **payload.positions())


class SegmentClose(SegmentWrite):
    """Ends a segment (``segments/{id}/close/`` of the API)."""

    def write(self, request, pk):
        return rules.close_segment(get_object_or_404(Segment, pk=pk))


class QuickReasonBody(serializers.Serializer):
    reason = s.ReasonField(required=True, help_text="ITO reason key.")
    take_over = serializers.IntegerField(
        required=False,
        help_text="The take-over open when the operator tapped (a tap kept while offline).",
    )


class QuickReason(SegmentWrite):
    """A quick reason: the server picks the leg's open take-over and answers with it."""

    def write(self, request, pk):
        leg = get_object_or_404(Leg, pk=pk)
        body = checked(QuickReasonBody, request).validated_data
        seen = body.get("take_over")
        return rules.annotate_open_take_over(leg, seen=seen, ito_reason=body["reason"])


class EndingQuery(serializers.Serializer):
    action = serializers.ChoiceField(choices=sorted(ACTIONS))
    id = serializers.IntegerField(min_value=1)


class Ending(GuiView):
    """What an action would end, asked before it is done (nothing is written):
    ``?action=end-event|end-shift|end-leg&id=`` of the row, ``?action=new-leg&id=``
    of the shift.  ``rosbridge_app.selectors.ending``."""

    def get(self, request):
        query = EndingQuery(data=request.query_params)
        query.is_valid(raise_exception=True)
        action = query.validated_data["action"]
        row = get_object_or_404(ACTIONS[action][0], pk=query.validated_data["id"])
        return Response(ending(action, row))


class SegmentAttachments(GuiView):
    """What the segment dialog shows beside the annotation, in one request: the
    segment's notes, and the images and snapshots of its master (a reason shares
    its master's), each as the REST list of that kind shows them."""

    def get(self, request, pk):
        segment = get_object_or_404(Segment, pk=pk)
        master = segment.master_id
        context = {"request": request}
        notes = Note.objects.select_related("author").filter(segment=segment)
        return Response(
            {
                "segment": segment.pk,
                "master": master,
                "notes": NoteSerializer(notes, many=True, context=context).data,
                "images": ImageSerializer(
                    Image.objects.filter(segment_id=master), many=True, context=context
                ).data,
                "recordings": RecordingSerializer(
                    Recording.objects.filter(segment_id=master), many=True, context=context
                ).data,
            }
        )


class ShiftLocalMap(GuiView):
    """The shift's newest map, where its corners lie, and the GPS overlay if known."""

    def get(self, request, pk):
        shift = get_object_or_404(Shift, pk=pk)
        image = current_map(shift)
        data = None
        if image is not None:
            data = {
                "id": image.pk,
                "url": image.image.url,
                "frame": image.frame,
                "width": image.width,
                "height": image.height,
                "resolution": image.resolution,
                "origin": [image.origin_x, image.origin_y, image.origin_yaw],
                "corners": {k: list(v) for k, v in map_corners(image).items()},
            }
        return Response({"shift": shift.pk, "map": data, "overlay": overlay(shift, image)})


class Basemaps(GuiView):
    """The layers of the map's switcher; ``?event=`` (repeatable: the fleet's events)
    marks the default those test events start on."""

    def get(self, request):
        events = request.query_params.getlist("event")
        if not all(event.isdigit() for event in events):
            raise ValidationError({"event": [_("Give test event ids.")]})
        return Response({"layers": layer_list([int(event) for event in events])})


class CollectorStatus(GuiView):
    """The collector of a vehicle, and whether logging may be switched now."""

    def get(self, request):
        vehicle = request.query_params.get("vehicle")
        leg_id = request.query_params.get("leg")
        if not (vehicle or "").isdigit():
            raise ValidationError({"vehicle": [_("Give the vehicle id.")]})
        collector = (
            collectors(Vehicle.objects.filter(pk=int(vehicle)).first())
            .order_by("-last_seen")
            .first()
        )
        leg = Leg.objects.filter(pk=int(leg_id)).first() if (leg_id or "").isdigit() else None
        allowed, reason = logging_control(collector, leg)
        can_snapshot, snapshot_reason = snapshot_control(collector)
        return Response(
            {
                "collector": collector_status(collector) if collector else None,
                "parameters": parameter_rows(collector) if collector else [],
                "can_toggle": allowed,
                "reason": reason,
                "can_snapshot": can_snapshot,
                "snapshot_reason": snapshot_reason,
                "stores_nothing": stores_nothing(collector),
            }
        )


class Forms(GuiView):
    """The fields of the dialogs (test event, shift, leg, report), from serializers."""

    def get(self, request):
        # ?event=<id>: the leg dialog offers that test event's test cases.
        event = request.query_params.get("event", "")
        test_event_id = int(event) if event.isdigit() else None
        return Response(gui_forms(getattr(request.user, "personnel", None), test_event_id))


class TestCaseAreas(GuiView):
    """The test cases with an area, for the place search to pick one."""

    def get(self, request):
        return Response({"cases": test_case_areas()})


class TestCaseRoutes(GuiView):
    """The test cases with a planned route, for the route comparison to pick one."""

    def get(self, request):
        return Response({"cases": test_case_routes()})


class Fleet(GuiView):
    """Every vehicle logging now: where it is, its mode, its last take-over, its leg."""

    def get(self, request):
        return Response({"vehicles": fleet()})


class CollectorCommands(GuiView):
    """Start/stop logging, parameter changes and snapshots, handed to the collector."""

    write_role = roles.OPERATOR

    def post(self, request, pk):
        collector = get_object_or_404(Collector, pk=pk)
        kind = request.data.get("kind")
        arguments = request.data.get("arguments") or {}
        if not isinstance(arguments, dict):
            raise ValidationError({"arguments": [_("Give the arguments as an object.")]})
        leg_id = request.data.get("leg")
        leg = Leg.objects.filter(pk=leg_id).first() if isinstance(leg_id, int) else None
        command = issue_command(collector, kind, arguments, user=request.user, leg=leg)
        return Response({"id": command.pk, "kind": command.kind}, status=202)
