from telemetry.models.figures import SegmentFigures, ThinnedSegment
from telemetry.models.images import Image
from telemetry.models.maps import MapImage
from telemetry.models.poses import LocalPose, Pose
from telemetry.models.recordings import Recording

__all__ = [
    "Image",
    "LocalPose",
    "MapImage",
    "Pose",
    "Recording",
    "SegmentFigures",
    "ThinnedSegment",
]
