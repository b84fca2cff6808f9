"""A single pose the quick way: checked by pydantic, stored by one statement.

Both ways in take it: the API view (``POST poses/``) and the production
server's lean route for the same address (ftt_site.pose_route).  None means
"not the whole answer" (a field it does not accept, an unknown segment or
pose source, another vehicle's segment for a robot, another database); the
view then checks the request in full and answers with its messages.
"""

from rest_framework import status

from telemetry.api import serializers as s
from telemetry.services import recording

# Its fields are built and bound once: a serializer made per answer deep-copies
# every declared field first, a third of the answer's time.  Answering reads
# the fields only, so the threads of a process share it.
_ANSWER = s.PoseByIdSerializer()


def store_sent(user, data) -> tuple[dict, int] | None:
    """The answer (body, status) for a pose sent by ``user``, stored; or None."""
    sent = s.sent_pose(data)
    if sent is None:
        return None
    segment_id, fix, source_id = sent
    stored = recording.record_pose_at(segment_id, fix, source_id, writer=user)
    if stored is None:
        return None
    pose, new = stored
    code = status.HTTP_201_CREATED if new else status.HTTP_200_OK
    return _ANSWER.to_representation(pose), code
