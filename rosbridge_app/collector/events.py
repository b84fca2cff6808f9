"""What the collector (or a bag import) has decided to record.

An event is plain data: a kind, the wall-clock time it happened, a uid that
becomes the row's uid (so writing it twice stores it once), a JSON-able dict
and, for pictures, bytes.  Heavy conversions (PNG/JPEG encoding) are deferred
in ``render`` so the ROS callbacks stay fast; :meth:`Event.prepare` runs them.
"""

import random
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime

# data: mode, robot_stamp, start_uncertainty (s), gps [lon, lat] | None, local [x, y, frame] | None
MODE = "mode"
GPS_FIX = "gps"  # data: lon, lat, alt, status, accuracy, robot_stamp
LOCAL_POSE = "local"  # data: x, y, yaw, frame, robot_stamp
MAP = "map"  # data: frame, width, height, resolution, origin_*, robot_stamp, checksum; blob PNG
IMAGE = "image"  # data: master (uid of the mode event), suffix, description, robot_stamp; blob
# data: master (uid or None: the open one), reason, path of the pending MCAP file,
# start, end (ISO), topics {topic: {type, count}}
RECORDING = "recording"
START = "start"
STOP = "stop"
KINDS = (MODE, GPS_FIX, LOCAL_POSE, MAP, IMAGE, RECORDING, START, STOP)
# Events that open or close a segment: they move the positions after them to
# another master, and an operator waits to see them (spooled at once).
SEGMENT_CHANGES = frozenset({MODE, START, STOP})

_STAMP_KEYS = ("robot_stamp",)


def new_uid() -> uuid.UUID:
    """A random (version 4) uid without a system call: uuid4() reads the kernel's
    random source for every one, which a 1 kHz GPS pays for in its receive
    thread.  Python's generator is seeded from that source once per process."""
    return uuid.UUID(bytes=random.randbytes(16), version=4)


@dataclass
class Event:
    kind: str
    at: datetime
    data: dict = field(default_factory=dict)
    blob: bytes | None = None
    uid: uuid.UUID = field(default_factory=new_uid)
    render: Callable[[], tuple[dict, bytes]] | None = field(default=None, repr=False)

    def prepare(self) -> "Event":
        """Run the deferred conversion; an event that cannot be converted raises."""
        if self.render is not None:
            extra, self.blob = self.render()
            self.data.update(extra)
            self.render = None
        return self

    def to_record(self) -> tuple[str, str, str, dict, bytes | None]:
        data = dict(self.data)
        for key in _STAMP_KEYS:
            if isinstance(data.get(key), datetime):
                data[key] = data[key].isoformat()
        return self.kind, self.at.isoformat(), str(self.uid), data, self.blob

    @classmethod
    def from_record(cls, kind: str, at: str, uid: str, data: dict, blob) -> "Event":
        for key in _STAMP_KEYS:
            if isinstance(data.get(key), str):
                data[key] = datetime.fromisoformat(data[key])
        return cls(kind, datetime.fromisoformat(at), data, blob, uuid.UUID(uid))
