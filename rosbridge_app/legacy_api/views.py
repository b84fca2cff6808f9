"""One view per address of the original's robot API (docs/api.md)."""

import hashlib
import uuid

from rest_framework.authentication import BaseAuthentication
from rest_framework.permissions import BasePermission
from rest_framework.response import Response
from rest_framework.views import APIView

from common import roles
from common.api.authentication import token_account
from common.retries import stored_row
from events.services import segments
from events.services.segments import GpsPosition, LocalPosition
from rosbridge_app.legacy_api import fields, targets
from rosbridge_app.legacy_api.answers import LegacyRefusal, info, refusal, warn
from rosbridge_app.legacy_api.fields import CURRENT_LEG, CURRENT_SEGMENT, CURRENT_SHIFT
from telemetry.models import Image
from telemetry.pictures import greyscale_png
from telemetry.services import attachments, map_images, pose_writes

# The original's segment_type ids.
MODE_OF_TYPE = {1: "ito", 2: "auto"}
# Row uids made from what the node sends, so a request it repeats after a lost
# answer stores nothing twice.  Track points name their master too: a retry is
# known by its uid within its segment, and the same stamps sent into a new leg
# are new data.
UIDS = uuid.UUID("6f1d1c52-1d0b-4c8e-9a51-2a8f3c7e9b10")


class PathToken(BaseAuthentication):
    """The robot account's API token, from the address (the node cannot send headers)."""

    def authenticate(self, request):
        return token_account(request.parser_context["kwargs"]["token"])

    def authenticate_header(self, request):
        return "Token"


class RobotsOnly(BasePermission):
    message = "Only a robot account's token opens the original's robot API."

    def has_permission(self, request, view):
        return roles.is_robot(request.user)


class LegacyView(APIView):
    authentication_classes = [PathToken]
    permission_classes = [RobotsOnly]
    # The node sends JSON under any Content-Type; fields.body_of reads it.
    parser_classes = []
    # The original's API, documented in docs/api.md; not part of FTT's OpenAPI schema.
    schema = None

    def get_exception_handler(self):
        return refusal

    def uid(self, kind: str, *parts) -> uuid.UUID:
        vehicle = targets.vehicle_of(self.request.user)
        return uuid.uuid5(UIDS, "|".join(map(str, (vehicle.pk, kind, *parts))))


class SegmentView(LegacyView):
    def post(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "leg_id", "segment_type_id")
        mode = MODE_OF_TYPE.get(fields.whole(data, "segment_type_id"))
        if mode is None:
            raise LegacyRefusal("UnsupportedError", "Unknown robot mode; send 1 (ITO) or 2 (AUTO).")
        leg = targets.leg(request.user, fields.entry_id(data, "leg_id", CURRENT_LEG))
        stamp = fields.robot_time(data, "orig_starttime_secs")
        gps = _position(data, "lng", "lat", GpsPosition)
        report = segments.report_mode(
            leg,
            mode,
            robot_stamp=stamp,
            gps=gps,
            local=_position(data, "local_x", "local_y", LocalPosition),
        )
        if report.changed:
            if gps is not None:
                # The node's newest fix at the switch, which it never posts as a
                # pose: without it the new take-over's track would start up to
                # send_pose_period later.
                fix = pose_writes.GpsFix(
                    longitude=gps.longitude,
                    latitude=gps.latitude,
                    robot_stamp=stamp,
                    uid=self.uid("switch", report.master.pk, stamp, gps.longitude, gps.latitude),
                )
                pose_writes.store_poses(report.master, [fix])
            return info(f"Created {mode.upper()} parent segment entry.")
        return info(f"The {mode.upper()} segment is open already; nothing changed.")

    def put(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "id", "action")
        pk = fields.entry_id(data, "id", CURRENT_SEGMENT)
        action = data["action"]
        if action == "edit":
            raise LegacyRefusal(
                "UnsupportedError", "Take-overs are annotated in FTT's cockpit or REST API."
            )
        if action != "close":
            raise LegacyRefusal("KeyValueError", "action must be 'close' or 'edit'.")
        if pk is None:
            if segments.close_open_master(targets.leg(request.user, None)) is None:
                raise LegacyRefusal("LogError", "No open segment entry. Aborted.")
            return info("Closed segment open entries.")
        segment = targets.segment(request.user, pk)
        if segment.end is not None:
            raise LegacyRefusal("LogError", f"Log entry segment {pk} is closed. Aborted.")
        segments.close_segment(segment)
        return info(f"Closed segment {pk}.")


class PoseView(LegacyView):
    def post(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "segment_id", "lat", "lng", "orig_secs")
        segment = targets.segment(
            request.user, fields.entry_id(data, "segment_id", CURRENT_SEGMENT)
        )
        lng, lat = fields.number(data, "lng"), fields.number(data, "lat")
        stamp = fields.robot_time(data, "orig_secs")
        fix = pose_writes.GpsFix(
            longitude=lng,
            latitude=lat,
            robot_stamp=stamp,
            uid=self.uid("pose", segment.master_id, stamp, lng, lat),
        )
        if pose_writes.store_poses(segment, [fix]):
            return info("Created pose entry.")
        return info("This pose is stored already.")


class LocalPoseView(LegacyView):
    def post(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "segment_id", "frame_id", "x", "y", "orig_secs")
        segment = targets.segment(
            request.user, fields.entry_id(data, "segment_id", CURRENT_SEGMENT)
        )
        x, y = fields.number(data, "x"), fields.number(data, "y")
        if x == 0 and y == 0:
            return warn("A local pose at exactly (0, 0) is a failed TF lookup; not stored.")
        stamp = fields.robot_time(data, "orig_secs")
        frame = fields.text(data, "frame_id").lstrip("/")
        pose = pose_writes.MapPose(
            x=x,
            y=y,
            frame=frame,
            robot_stamp=stamp,
            uid=self.uid("local", segment.master_id, stamp, x, y),
        )
        if pose_writes.store_local_poses(segment, [pose]):
            return info("Created local_pose entry.")
        return info("This local pose is stored already.")


class MapImageView(LegacyView):
    PLACEMENT = ("width", "height", "resolution", "origin_x", "origin_y")

    def post(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "shift_id", "frame_id", *self.PLACEMENT, "image_data")
        return self._store(request, data)

    def put(self, request, token):
        # The node sends every field; the original also took a partial update.
        data = fields.body_of(request)
        fields.required(data, "shift_id", "image_data")
        return self._store(request, data)

    def _store(self, request, data):
        shift = targets.shift(request.user, fields.entry_id(data, "shift_id", CURRENT_SHIFT))
        newest = shift.maps.order_by("-received", "-id").first()
        placement = {}
        for name in self.PLACEMENT:
            if name in data:
                placement[name] = (
                    fields.whole(data, name)
                    if name in ("width", "height")
                    else fields.number(data, name)
                )
            elif newest is not None:
                placement[name] = getattr(newest, name)
            else:
                raise LegacyRefusal(
                    "KeyError", f"Missing field {name}: the shift has no map to take it from."
                )
        frame = fields.text(data, "frame_id").lstrip("/") or (newest.frame if newest else "map")
        _, stored = map_images.store_map(
            shift,
            png=greyscale_png(fields.picture(data, "image_data")),
            frame=frame,
            robot_stamp=fields.robot_time(data, "orig_secs"),
            **placement,
        )
        return info("Stored map_image entry." if stored else "The map is unchanged.")


class ImageView(LegacyView):
    def post(self, request, token):
        data = fields.body_of(request)
        fields.required(data, "segment_id", "image_data")
        segment = targets.segment(
            request.user, fields.entry_id(data, "segment_id", CURRENT_SEGMENT)
        )
        content = fields.picture(data, "image_data")
        stamp = fields.robot_time(data, "orig_secs")
        description = fields.text(data, "description") or fields.text(data, "image_filename")
        # The node sends its image buffer again at every switch, even when the
        # camera stalled: the same frame is stored once, on its first take-over.
        uid = self.uid("image", stamp, hashlib.sha256(content).hexdigest())
        vehicle = targets.vehicle_of(request.user)
        if stored_row(Image, uid, segment__leg__shift__vehicle=vehicle):
            return info("This frame is stored already, with the take-over it came first with.")
        attachments.attach_image(
            segment, content=content, description=description, robot_stamp=stamp, uid=uid
        )
        return info("Created image entry.")


class RobotStateView(LegacyView):
    def get(self, request, token):
        master = targets.segment(request.user, None)
        return Response([master.segment_type_id.upper()])


def _position(data: dict, first: str, second: str, kind):
    """A position the node sent, or None: it sends null for none, and (0, 0) for a
    failed lookup."""
    a = fields.number(data, first, optional=True)
    b = fields.number(data, second, optional=True)
    if a is None or b is None or (a == 0 and b == 0):
        return None
    return kind(a, b)
