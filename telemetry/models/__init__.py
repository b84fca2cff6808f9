from telemetry.models.images import Image
from telemetry.models.maps import MapImage
from telemetry.models.poses import LocalPose, Pose

__all__ = ["Image", "LocalPose", "MapImage", "Pose"]
