"""REST endpoints for configuration, catalogues and the log hierarchy."""

from django.http import Http404
from django.utils.translation import gettext as _
from drf_spectacular.utils import (
    OpenApiParameter,
    OpenApiResponse,
    extend_schema,
    extend_schema_view,
)
from rest_framework import status
from rest_framework.decorators import action
from rest_framework.exceptions import NotFound
from rest_framework.response import Response

from events.api import serializers as s
from events.api.filters import (
    BBoxFilter,
    LegFilter,
    NoteFilter,
    SearchFilterBackend,
    SegmentFilter,
    ShiftFilter,
    TestEventFilter,
    search_params,
)
from events.api.found_files import KINDS, found_file
from events.api.viewsets import ServiceBaseViewSet, ServiceUpdateMixin, ServiceViewSet
from events.models import (
    ItoReason,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    SegmentType,
    Shift,
    TestEvent,
    Vehicle,
    Weather,
)
from events.selectors import logs as log_selectors
from events.selectors.found_segments import found_rows
from events.selectors.history import history_of
from events.services import configuration, finality, logs, notes, segments

NO_BODY = {"request": None}


# --- configuration and catalogues -----------------------------------------------------------


class ConfigurationViewSet(ServiceViewSet):
    def create_with_service(self, data):
        return configuration.create_configuration(self.queryset.model, **data)

    def update_with_service(self, instance, data):
        return configuration.update_configuration(instance, **data)

    def delete_with_service(self, instance):
        configuration.delete_configuration(instance)


class PersonnelViewSet(ConfigurationViewSet):
    queryset = Personnel.objects.all()
    serializer_class = s.PersonnelSerializer


class PerformerViewSet(ConfigurationViewSet):
    queryset = Performer.objects.all()
    serializer_class = s.PerformerSerializer


class VehicleViewSet(ConfigurationViewSet):
    """Vehicles are addressed by id or by key (``/api/vehicles/husky-1/``)."""

    queryset = Vehicle.objects.all()
    serializer_class = s.VehicleSerializer
    lookup_value_regex = "[-a-zA-Z0-9_]+"
    # Its own vehicle only (RobotTargetPermission): where to log now.
    robot_actions = ("retrieve", "current_leg")

    def get_object(self):
        value = self.kwargs[self.lookup_url_kwarg or self.lookup_field]
        queryset = self.filter_queryset(self.get_queryset())
        vehicle = None
        if value.isascii() and value.isdigit():
            vehicle = queryset.filter(pk=int(value)).first()
        if vehicle is None:
            vehicle = queryset.filter(key=value).first()
        if vehicle is None:
            raise Http404
        self.check_object_permissions(self.request, vehicle)
        return vehicle

    @extend_schema(
        responses={
            200: s.CurrentLegSerializer,
            404: OpenApiResponse(description="The vehicle has no open leg."),
        }
    )
    @action(detail=True, methods=["get"], url_path="current-leg")
    def current_leg(self, request, pk=None):
        """The open leg of the vehicle's open shift (where its robot logs now)."""
        leg = log_selectors.open_leg_for_vehicle(self.get_object())
        if leg is None:
            raise NotFound(_("This vehicle has no open leg; start a shift and a leg first."))
        leg.open_segment = log_selectors.open_master(leg)
        return self.respond(leg, s.CurrentLegSerializer)


class PoseSourceViewSet(ConfigurationViewSet):
    queryset = PoseSource.objects.all()
    serializer_class = s.PoseSourceSerializer
    robot_actions = ("list", "retrieve")


class CatalogueViewSet(ConfigurationViewSet):
    lookup_value_regex = "[-a-zA-Z0-9_]+"
    pagination_class = None
    robot_actions = ("list", "retrieve")


class WeatherViewSet(CatalogueViewSet):
    queryset = Weather.objects.all()
    serializer_class = s.WeatherSerializer


class ItoReasonViewSet(CatalogueViewSet):
    queryset = ItoReason.objects.all()
    serializer_class = s.ItoReasonSerializer


class SegmentTypeViewSet(CatalogueViewSet):
    """The two modes are fixed by the logging rules: descriptions and colours can change,
    rows cannot be added or removed."""

    queryset = SegmentType.objects.all()
    serializer_class = s.SegmentTypeSerializer
    http_method_names = ["get", "put", "patch", "head", "options"]


# --- log hierarchy ------------------------------------------------------------------------


class HistoryMixin:
    """``…/{id}/history/``: who changed the row, when, through what and why."""

    @extend_schema(responses={200: OpenApiResponse(description="Change history, newest first")})
    @action(detail=True, methods=["get"])
    def history(self, request, pk=None):
        return Response(history_of(self.get_object()))


class TestEventViewSet(HistoryMixin, ServiceViewSet):
    queryset = TestEvent.objects.all()
    serializer_class = s.TestEventSerializer
    filterset_class = TestEventFilter

    def create_with_service(self, data):
        return logs.create_test_event(**data)

    def update_with_service(self, instance, data):
        return logs.update_test_event(instance, **data)

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def close(self, request, pk=None):
        """End the test event and everything still open in it."""
        return self.respond(logs.close_test_event(self.get_object()))

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def reopen(self, request, pk=None):
        """Open a closed test event again; its shifts stay closed."""
        return self.respond(logs.reopen_test_event(self.get_object()))

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def finalise(self, request, pk=None):
        """Make a closed test event final: read-only for operators, taxonomy frozen."""
        return self.respond(finality.finalise_test_event(self.get_object(), by=request.user))


class ShiftViewSet(HistoryMixin, ServiceViewSet):
    queryset = Shift.objects.all()
    serializer_class = s.ShiftSerializer
    filterset_class = ShiftFilter
    robot_actions = ("retrieve",)

    def create_with_service(self, data):
        return logs.create_shift(**data)

    def update_with_service(self, instance, data):
        return logs.update_shift(instance, **data)

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def close(self, request, pk=None):
        """End the shift and its open leg and segments."""
        return self.respond(logs.close_shift(self.get_object()))


class LegViewSet(HistoryMixin, ServiceViewSet):
    # The shift tells a leg's vehicle (a robot account's check) without another query.
    queryset = Leg.objects.select_related("shift")
    serializer_class = s.LegSerializer
    filterset_class = LegFilter
    robot_actions = ("retrieve", "mode")

    def create_with_service(self, data):
        return logs.create_leg(**data)

    def update_with_service(self, instance, data):
        return logs.update_leg(instance, **data)

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def close(self, request, pk=None):
        """End the leg and its open segments."""
        return self.respond(logs.close_leg(self.get_object()))

    @extend_schema(
        request=s.ModeReportSerializer,
        responses={201: s.ModeResultSerializer, 200: s.ModeResultSerializer},
    )
    @action(detail=True, methods=["post"])
    def mode(self, request, pk=None):
        """The robot reports its mode. A change closes the open master segment and opens
        one of the new mode (201); repeating the open mode changes nothing (200)."""
        leg = self.get_object()
        payload = self.payload(s.ModeReportSerializer)
        data = payload.validated_data
        outcome = segments.report_mode(
            leg,
            data["mode"],
            robot_stamp=data.get("robot_stamp"),
            reason=s.reason_key(data),
            uid=data.get("uid"),
            **payload.positions(),
        )
        result = {"changed": outcome.changed, "segment": outcome.master}
        code = status.HTTP_201_CREATED if outcome.changed else status.HTTP_200_OK
        return self.respond(result, s.ModeResultSerializer, code)

    @extend_schema(request=s.ManualSegmentSerializer, responses={201: s.SegmentSerializer})
    @action(detail=True, methods=["post"], url_path="manual-segment")
    def manual_segment(self, request, pk=None):
        """An operator records a take-over: a new ITO reason, switching to ITO if needed.
        Answers with the new ITO child segment."""
        leg = self.get_object()
        payload = self.payload(s.ManualSegmentSerializer)
        data = payload.validated_data
        child = segments.new_manual_segment(
            leg,
            reason=s.reason_key(data),
            uid=data.get("uid"),
            at=payload.recorded_at(),
            **payload.positions(),
        )
        return self.respond(child, s.SegmentSerializer, status.HTTP_201_CREATED)


@extend_schema_view(
    partial_update=extend_schema(
        description="Annotate an ITO reason (child segment): reason, obstacle, lighting, "
        "slope. Masters and AUTO segments answer 409."
    )
)
class SegmentViewSet(HistoryMixin, ServiceUpdateMixin, ServiceBaseViewSet):
    """Segments are opened by ``legs/{id}/mode``, ``legs/{id}/manual-segment`` and
    ``segments/{id}/children``; PATCH annotates an ITO reason."""

    queryset = Segment.objects.all()
    serializer_class = s.SegmentSerializer
    filterset_class = SegmentFilter
    filter_backends = [SearchFilterBackend, BBoxFilter]
    bbox_filter_field = "start_position"
    http_method_names = ["get", "patch", "post", "delete", "head", "options"]
    robot_actions = ("retrieve",)
    # A search sent by POST only reads (common.api.permissions).
    read_actions = ("found",)
    # The file kind of ``found`` (events.api.filters.SearchFilterBackend).
    extra_params = ("as",)

    def update_with_service(self, instance, data):
        return segments.annotate_segment(instance, **data)

    @extend_schema(**NO_BODY)
    @action(detail=True, methods=["post"])
    def close(self, request, pk=None):
        """Closing a master also closes its children; closing a child ends only that reason."""
        return self.respond(segments.close_segment(self.get_object()))

    @extend_schema(
        parameters=[OpenApiParameter("as", str, enum=KINDS, description="file kind (geojson)")],
        responses={200: OpenApiResponse(description="GeoJSON FeatureCollection or CSV")},
    )
    @action(detail=False, methods=["get", "post"])
    def found(self, request):
        """Every segment the list's filters find (``within``, ``in_bbox``, ``reason``,
        ``vehicle``, ``version``, times), unpaged, as a GeoJSON or CSV file.  POST
        takes the same parameters in its body, for an area too large for the URL."""
        rows = found_rows(self.filter_queryset(self.get_queryset()))
        return found_file(request, rows, search_params(request, self).get("as", "geojson"))

    @extend_schema(request=s.ChildSerializer, responses={201: s.SegmentSerializer})
    @action(detail=True, methods=["post"])
    def children(self, request, pk=None):
        """Add another take-over reason to an open ITO master."""
        master = self.get_object()
        payload = self.payload(s.ChildSerializer)
        child = segments.add_ito_child(master, reason=s.reason_key(payload.validated_data))
        return self.respond(child, s.SegmentSerializer, status.HTTP_201_CREATED)


class NoteViewSet(HistoryMixin, ServiceViewSet):
    queryset = Note.objects.select_related("author")
    serializer_class = s.NoteSerializer
    filterset_class = NoteFilter

    def create_with_service(self, data):
        return notes.add_note(
            data["segment"],
            text=data["text"],
            author=data.get("author"),
            uid=data.get("uid"),
            by=self.request.user,
        )

    def update_with_service(self, instance, data):
        if "text" not in data:
            return instance
        return notes.edit_note(instance, text=data["text"], by=self.request.user)

    def delete_with_service(self, instance):
        notes.delete_note(instance, by=self.request.user)
