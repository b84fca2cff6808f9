"""Read-only JSON the GUI needs beyond the REST API: tracks of a leg drawn in
one request, and the local map with its placement on the GPS map.

Same authentication, roles and error shape as /api/ (DRF views with the
project defaults); the numbers come from selectors, never from here.
"""

from django.shortcuts import get_object_or_404
from drf_spectacular.utils import extend_schema
from rest_framework.exceptions import ValidationError
from rest_framework.response import Response
from rest_framework.views import APIView

from events import roles
from events.errors import RuleViolation
from events.models import Leg, SegmentType, Shift, Vehicle
from reports.selectors.tracks import GPS, LOCAL, load_tracks, path_length
from rosbridge_app.models import Collector
from rosbridge_app.selectors.collectors import collector_status, collectors
from rosbridge_app.selectors.control import (
    check_parameter_values,
    logging_control,
    parameter_rows,
)
from rosbridge_app.services.collectors import issue_command
from telemetry.selectors.maps import current_map
from telemetry.selectors.overlay import map_corners, overlay


@extend_schema(exclude=True)
class GuiView(APIView):
    """Internal to the GUI pages, so kept out of the documented /api/ schema."""


class LegTracks(GuiView):
    """Every master segment's GPS and local track, with its driven distance."""

    def get(self, request, pk):
        leg = get_object_or_404(Leg, pk=pk)
        masters = dict(
            leg.segments.filter(parent__isnull=True).values_list("id", "segment_type_id")
        )
        gps = load_tracks(list(masters), GPS)
        local = load_tracks(list(masters), LOCAL)
        segments = {}
        for segment_id, mode in masters.items():
            g, lo = gps.get(segment_id), local.get(segment_id)
            distance = None
            if g is not None and len(g) > 1:
                distance = path_length(g.x, g.y, GPS)
            elif lo is not None and len(lo) > 1:
                distance = path_length(lo.x, lo.y, LOCAL)
            segments[segment_id] = {
                "mode": mode,
                "ito": mode == SegmentType.ITO,
                # [lat, lon]: the order Leaflet takes.
                "gps": [] if g is None else [[y, x] for x, y in zip(g.x, g.y, strict=True)],
                "local": [] if lo is None else [[x, y] for x, y in zip(lo.x, lo.y, strict=True)],
                "distance_m": distance,
            }
        return Response({"leg": leg.pk, "segments": segments})


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


class CollectorStatus(GuiView):
    """The collector of a vehicle, and whether logging may be switched now."""

    def get(self, request):
        vehicle = request.query_params.get("vehicle")
        leg_id = request.query_params.get("leg")
        if not (vehicle or "").isdigit():
            raise ValidationError({"vehicle": ["Give the vehicle id."]})
        collector = (
            collectors(Vehicle.objects.filter(pk=int(vehicle)).first())
            .order_by("-last_seen")
            .first()
        )
        leg = Leg.objects.filter(pk=int(leg_id)).first() if (leg_id or "").isdigit() else None
        allowed, reason = logging_control(collector, leg)
        return Response(
            {
                "collector": collector_status(collector) if collector else None,
                "parameters": parameter_rows(collector) if collector else [],
                "can_toggle": allowed,
                "reason": reason,
            }
        )


class CollectorCommands(GuiView):
    """Start/stop logging and parameter changes, handed to the collector."""

    write_role = roles.OPERATOR

    def post(self, request, pk):
        collector = get_object_or_404(Collector, pk=pk)
        kind = request.data.get("kind")
        arguments = request.data.get("arguments") or {}
        if not isinstance(arguments, dict):
            raise ValidationError({"arguments": ["Give the arguments as an object."]})
        if kind in ("start_logging", "stop_logging"):
            leg_id = request.data.get("leg")
            leg = Leg.objects.filter(pk=leg_id).first() if isinstance(leg_id, int) else None
            allowed, reason = logging_control(collector, leg)
            if not allowed or (kind == "start_logging") == collector.logging:
                raise RuleViolation(reason or "Logging is already in that state.")
            if leg is not None:
                arguments.setdefault("leg", leg.pk)
        elif kind == "set_parameters":
            changes = arguments.get("parameters")
            if not isinstance(changes, dict):
                raise ValidationError({"parameters": ["Give the parameters to set as an object."]})
            arguments["parameters"] = check_parameter_values(collector, changes)
        command = issue_command(collector, kind, arguments, user=request.user)
        return Response({"id": command.pk, "kind": command.kind}, status=202)
