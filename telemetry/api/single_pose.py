"""``POST poses/``: one pose, stored and answered the same way whichever way it
came in (the API view, or the production server's route for the same address,
ftt_site.inbound.pose_route)."""

from rest_framework import status

from telemetry.api import serializers as s
from telemetry.services import pose_writes

# Its fields are built and bound once: a serializer made per answer deep-copies
# every declared field first.  Answering reads the fields only, so the threads
# of a process share it.
_ANSWER = s.PoseByIdSerializer()


def store(user, sent: tuple) -> tuple[dict, int]:
    """Store a pose as :func:`telemetry.api.serializers.sent_pose` gives it, sent
    by ``user``; the answer (body, status).  Raises what the API answers as
    4xx (an unknown segment, another vehicle's segment, a uid of another row)."""
    segment_id, fix, source_id = sent
    pose, new = pose_writes.store_pose(segment_id, fix, source_id, writer=user)
    return _ANSWER.to_representation(pose), status.HTTP_201_CREATED if new else status.HTTP_200_OK
