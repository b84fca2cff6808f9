"""REST endpoints for robot data (poses, maps, images) and the track views built on them."""

import django_filters as filters
from django.utils.translation import gettext as _
from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiParameter, OpenApiResponse, extend_schema
from rest_framework import serializers, status, viewsets
from rest_framework.decorators import action
from rest_framework.exceptions import NotFound
from rest_framework.parsers import FormParser, MultiPartParser
from rest_framework.response import Response

from common import geojson, roles
from events.api.filters import BBoxFilter, IdFilter, SearchFilterBackend, TimeRangeFilterSet
from events.api.serializers import PrimaryKeyField
from events.api.viewsets import ServiceBaseViewSet, ServiceCreateMixin
from events.models import Leg, Shift, TestEvent
from telemetry.api import serializers as s
from telemetry.api import single_pose
from telemetry.models import Image, LocalPose, MapImage, Pose, Recording
from telemetry.selectors import distances, tracks
from telemetry.selectors import maps as map_selectors
from telemetry.services import attachments, map_images, pose_writes
from telemetry.storage import keys

# --- filters ------------------------------------------------------------------------------


class SegmentDataFilter(TimeRangeFilterSet):
    """Rows hanging off a segment, filterable by any ancestor."""

    segment = IdFilter(field_name="segment_id")
    leg = IdFilter(field_name="segment__leg_id")
    shift = IdFilter(field_name="segment__leg__shift_id")
    test_event = IdFilter(field_name="segment__leg__shift__test_event_id")


class PoseFilter(SegmentDataFilter):
    class Meta:
        model = Pose
        fields = []
        time_fields = ["robot_stamp", "received"]


class LocalPoseFilter(SegmentDataFilter):
    frame = filters.CharFilter()

    class Meta:
        model = LocalPose
        fields = []
        time_fields = ["robot_stamp", "received"]


class ImageFilter(SegmentDataFilter):
    class Meta:
        model = Image
        fields = []
        time_fields = ["robot_stamp", "received"]


class RecordingFilter(SegmentDataFilter):
    class Meta:
        model = Recording
        fields = []
        time_fields = ["start", "received"]


class MapFilter(TimeRangeFilterSet):
    shift = IdFilter(field_name="shift_id")
    test_event = IdFilter(field_name="shift__test_event_id")

    class Meta:
        model = MapImage
        fields = []
        time_fields = ["robot_stamp", "received"]


# --- robot data ---------------------------------------------------------------------------


class RobotDataViewSet(ServiceCreateMixin, ServiceBaseViewSet):
    """Robot data is created and deleted, never edited."""

    def store_batch(self, request, serializer_class, store):
        stored = store(**self.payload(serializer_class).validated_data)
        return Response({"stored": stored}, status=status.HTTP_201_CREATED)


class PoseViewSet(RobotDataViewSet):
    queryset = Pose.objects.all()
    serializer_class = s.PoseSerializer
    filterset_class = PoseFilter
    filter_backends = [SearchFilterBackend, BBoxFilter]
    bbox_filter_field = "point"
    robot_actions = ("create", "batch")

    def create(self, request, *args, **kwargs):
        # The quick check first; what it refuses gets the serializer's field messages.
        sent = s.sent_pose(request.data)
        if sent is None:
            serializer = self.get_serializer(data=request.data)
            serializer.is_valid(raise_exception=True)
            sent = s.sent_ids(serializer.validated_data)
        return Response(*single_pose.store(request.user, sent))

    @extend_schema(request=s.PoseBatchSerializer, responses={201: s.BatchResultSerializer})
    @action(detail=False, methods=["post"])
    def batch(self, request):
        """Store many GPS fixes of one segment at once; known uids are skipped."""
        return self.store_batch(
            request,
            s.PoseBatchSerializer,
            lambda segment, poses, pose_source=None: pose_writes.store_poses(
                segment, [s.gps_fix(p) for p in poses], pose_source
            ),
        )


class LocalPoseViewSet(RobotDataViewSet):
    queryset = LocalPose.objects.all()
    serializer_class = s.LocalPoseSerializer
    filterset_class = LocalPoseFilter
    robot_actions = ("create", "batch")

    def create_with_service(self, data):
        return pose_writes.store_local_pose(data["segment"], s.map_pose(data))

    @extend_schema(request=s.LocalPoseBatchSerializer, responses={201: s.BatchResultSerializer})
    @action(detail=False, methods=["post"])
    def batch(self, request):
        """Store many map-frame poses of one segment at once; known uids are skipped."""
        return self.store_batch(
            request,
            s.LocalPoseBatchSerializer,
            lambda segment, poses: pose_writes.store_local_poses(
                segment, [s.map_pose(p) for p in poses]
            ),
        )


class MapImageViewSet(RobotDataViewSet):
    """Maps are uploaded as multipart/form-data with the PNG in ``image``."""

    queryset = MapImage.objects.all()
    serializer_class = s.MapImageSerializer
    filterset_class = MapFilter
    parser_classes = [MultiPartParser, FormParser]
    robot_actions = ("create",)

    def create(self, request, *args, **kwargs):
        serializer = self.get_serializer(data=request.data)
        serializer.is_valid(raise_exception=True)
        data = dict(serializer.validated_data)
        upload = data.pop("image")
        shift = data.pop("shift")
        map_image, stored = map_images.store_map(shift, png=upload.read(), **data)
        # An unchanged map (or a retried uid) is answered with the map already stored.
        code = status.HTTP_201_CREATED if stored else status.HTTP_200_OK
        return self.respond(map_image, code=code)

    @extend_schema(
        parameters=[OpenApiParameter("shift", OpenApiTypes.INT, required=True)],
        responses={200: s.MapImageSerializer, 404: OpenApiResponse(description="No map yet.")},
    )
    @action(detail=False, methods=["get"])
    def current(self, request):
        """The newest map of a shift: the one the GUI and the report draw."""
        shift = _parent(request.query_params, {"shift": Shift}, required=True)["shift"]
        map_image = map_selectors.current_map(shift)
        if map_image is None:
            raise NotFound(_("This shift has no map yet."))
        return self.respond(map_image)


class ImageViewSet(RobotDataViewSet):
    """Images are uploaded as multipart/form-data with the file in ``image``."""

    queryset = Image.objects.all()
    serializer_class = s.ImageSerializer
    filterset_class = ImageFilter
    parser_classes = [MultiPartParser, FormParser]
    robot_actions = ("create",)

    def create_with_service(self, data):
        upload = data["image"]
        return attachments.attach_image(
            data["segment"],
            content=upload.read(),
            description=data.get("description", ""),
            robot_stamp=data.get("robot_stamp"),
            uid=data.get("uid"),
        )

    def delete_with_service(self, instance):
        attachments.delete_image(instance)


class RecordingFileViewSet(ServiceBaseViewSet):
    """Black-box snapshots (MCAP) of the collector; written by the collector only."""

    queryset = Recording.objects.all()
    serializer_class = s.RecordingSerializer
    filterset_class = RecordingFilter

    def delete_with_service(self, instance):
        attachments.delete_recording(instance)


# --- tracks -------------------------------------------------------------------------------

PARENTS = {"leg": Leg, "shift": Shift, "test_event": TestEvent}
TRACK_PARAMETERS = [
    OpenApiParameter(name, OpenApiTypes.INT, description=f"Tracks of this {name}.")
    for name in PARENTS
]


class _ParentQuery(serializers.Serializer):
    leg = PrimaryKeyField(queryset=Leg.objects.all(), required=False)
    shift = PrimaryKeyField(queryset=Shift.objects.all(), required=False)
    test_event = PrimaryKeyField(queryset=TestEvent.objects.all(), required=False)


def _parent(params, allowed: dict, required: bool = False) -> dict:
    """Validate ``?leg=`` / ``?shift=`` / ``?test_event=`` query parameters."""
    query = _ParentQuery(data={k: params[k] for k in allowed if k in params})
    query.is_valid(raise_exception=True)
    found = {k: v for k, v in query.validated_data.items() if k in allowed}
    if required and len(found) != 1:
        names = " or ".join(allowed)
        raise serializers.ValidationError(
            {"non_field_errors": [(_("Give exactly one of %(names)s.") % {"names": names})]}
        )
    return found


def _segment_properties(segment) -> dict:
    return {
        "segment": segment.pk,
        "uid": str(segment.uid),
        "leg": segment.leg_id,
        "mode": segment.segment_type_id,
        "start": segment.start.isoformat(),
        "end": segment.end.isoformat() if segment.end else None,
    }


class TrackViewSet(viewsets.ViewSet):
    """GPS tracks as GeoJSON: one LineString feature per master segment."""

    read_role = roles.VIEWER

    @extend_schema(parameters=TRACK_PARAMETERS, responses={200: OpenApiTypes.OBJECT})
    def list(self, request):
        """A FeatureCollection with one feature per master segment that has poses, oldest
        first. Coordinates are [longitude, latitude] in time order (points without a fix are
        left out); a master with a single point is a Point."""
        parent = _parent(request.query_params, PARENTS, required=True)
        features = []
        # Whole legs: the distance rule needs each master's follower.
        masters = list(tracks.masters(**parent))
        loaded = tracks.load_tracks([m.pk for m in masters], keys.GPS_TRACK)
        paths = distances.measured_paths(masters, keys.GPS_TRACK, loaded)
        for track in tracks.segment_tracks(masters, keys.GPS_TRACK, loaded):
            coordinates = track.coordinates()
            properties = _segment_properties(track.segment)
            properties["point_count"] = len(coordinates)
            properties["distance_m"] = paths[track.segment.pk].distance
            features.append(
                geojson.feature(geojson.path(coordinates), properties, id=track.segment.pk)
            )
        return Response(geojson.collection(features))


class LocalTrackViewSet(viewsets.ViewSet):
    """Tracks in the map frame: per master segment, x and y arrays in time order."""

    read_role = roles.VIEWER

    @extend_schema(parameters=TRACK_PARAMETERS, responses={200: OpenApiTypes.OBJECT})
    def list(self, request):
        parent = _parent(request.query_params, PARENTS, required=True)
        result = []
        # Whole legs: the distance rule needs each master's follower.
        masters = list(tracks.masters(**parent))
        loaded = tracks.load_tracks([m.pk for m in masters], keys.LOCAL_TRACK)
        paths = distances.measured_paths(masters, keys.LOCAL_TRACK, loaded)
        for track in tracks.segment_tracks(masters, keys.LOCAL_TRACK, loaded):
            item = _segment_properties(track.segment)
            item.update(
                frame=track.frame,
                point_count=len(track),
                distance_m=paths[track.segment.pk].distance,
                x=track.x.tolist(),
                y=track.y.tolist(),
            )
            result.append(item)
        return Response({"tracks": result})
