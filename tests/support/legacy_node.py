"""The original FTT's ROS 2 node (``ros2api``), as its documentation describes it,
driven by a recording's messages instead of live topics.

It sends what the node sends, when the node sends it: a segment on the first
mode message and on every change, then its image buffer; the latest GPS fix
every ``send_pose_period`` seconds of recording time while a mode is known; a
map every ``send_map_period`` seconds when a new one arrived (POST first, PUT
after). The camera is a synthetic one that buffers ``image_buffer_size``
frames, one per ``image_buffer_step`` seconds.
"""

import base64
import io
from dataclasses import dataclass, field

import requests
from PIL import Image as PilImage

SEGMENT_TYPE = {1: 1, 2: 2}  # industrial RobotMode MANUAL=1 → ITO (1), AUTO=2 → AUTO (2)


def jpeg(shade: int, size=(32, 24)) -> str:
    out = io.BytesIO()
    PilImage.new("RGB", size, (shade, 255 - shade, 90)).save(out, format="JPEG")
    return base64.b64encode(out.getvalue()).decode()


@dataclass
class LegacyNode:
    address: str  # params.server_address, e.g. "127.0.0.1:8000/legacy/<token>"
    send_pose_period: float = 2.0
    image_buffer_size: int = 3
    image_buffer_step: float = 1.0
    answers: list = field(default_factory=list)
    mode: int | None = None
    last_fix: tuple | None = None
    next_pose: float | None = None
    images: list = field(default_factory=list)
    image_count: int = 0

    def send(self, verb: str, path: str, body: dict | None = None) -> requests.Response:
        answer = requests.request(verb, f"http://{self.address}/{path}", json=body, timeout=30)
        self.answers.append((verb, path, answer.status_code, answer.text))
        return answer

    def on_fix(self, t: float, lng: float, lat: float, stamp: float) -> None:
        self.last_fix = (lng, lat, stamp)
        self._tick(t)

    def on_camera(self, t: float) -> None:
        if self.images and t - self.images[-1][0] <= self.image_buffer_step:
            return
        self.images.append((t, jpeg(int(t * 7) % 255)))
        del self.images[: -self.image_buffer_size]

    def on_mode(self, t: float, value: int) -> None:
        if self.mode == value:
            return
        lng, lat, _ = self.last_fix or (None, None, None)
        answer = self.send(
            "POST",
            "segment",
            {
                "leg_id": "Current Leg",
                "segment_type_id": SEGMENT_TYPE[value],
                "ito_reason_id": 11,
                "lng": lng,
                "lat": lat,
                "local_x": None,
                "local_y": None,
                "orig_starttime_secs": t,
            },
        )
        if answer.status_code != 200:
            return
        if self.mode is None:
            self.next_pose = t + self.send_pose_period
        self.mode = value
        for stamp, data in self.images:
            self.image_count += 1
            self.send(
                "POST",
                "image",
                {
                    "segment_id": "Current Segment",
                    "image_filename": f"rgb_img{self.image_count}",
                    "image_data": data,
                    "description": "Automatic image capture for segment transition",
                    "orig_secs": stamp,
                },
            )

    def _tick(self, t: float) -> None:
        while self.next_pose is not None and t >= self.next_pose:
            self.next_pose += self.send_pose_period
            if self.last_fix is None:
                continue
            lng, lat, stamp = self.last_fix
            answer = self.send(
                "POST",
                "pose",
                {
                    "segment_id": "Current Segment",
                    "lng": lng,
                    "lat": lat,
                    "pose_source_id": 1,
                    "orig_secs": stamp,
                },
            )
            if answer.status_code == 200:
                self.last_fix = None

    def stop(self) -> None:
        self.send("PUT", "segment", {"id": "Current Segment", "action": "close"})
