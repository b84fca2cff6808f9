"""ROS messages → values the recording services take.

Everything here works on any object with the message's field names, so the
same functions serve rclpy messages (live) and rosbags messages (bag files).
"""

import hashlib
import io
import math
from datetime import UTC, datetime

import numpy as np
from django.utils.translation import gettext as _
from PIL import Image as PilImage

from events.services.segments import LATITUDE_RANGE, LONGITUDE_RANGE
from rosbridge_app.collector.tf_buffer import Transform, yaw_of
from telemetry.models import MapImage

# sensor_msgs/NavSatStatus
# Jazzy's default value: a driver that never sets the status sends it.
STATUS_UNKNOWN = -2
STATUS_NO_FIX = -1
KNOWN_FIX_STATUSES = (0, 1, 2)
COVARIANCE_TYPE_UNKNOWN = 0

JPEG_QUALITY = 85


def stamp_ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def stamp_to_datetime(stamp) -> datetime | None:
    """A header stamp as an aware datetime; None for an unset (zero) stamp."""
    ns = stamp_ns(stamp)
    if ns <= 0:
        return None
    try:
        return datetime.fromtimestamp(ns / 1e9, tz=UTC)
    except (OverflowError, OSError, ValueError):
        return None


def byte_array(data) -> np.ndarray:
    """uint8 view of a message's byte field (bytes, array.array, numpy or a list)."""
    if isinstance(data, list | tuple):
        return np.asarray(data, dtype=np.uint8)
    return np.frombuffer(data, dtype=np.uint8)


def _finite(*values) -> bool:
    return all(isinstance(v, int | float) and math.isfinite(v) for v in values)


# --- GPS ------------------------------------------------------------------------------------


def navsat_fix(msg) -> dict | None:
    """The usable part of a NavSatFix, or None when it must not be recorded
    (no fix, non-finite or impossible coordinates).  A status FTT does not know,
    STATUS_UNKNOWN included, is stored as a plain fix: dropping every fix of a
    driver that leaves the status unset would lose the robot's whole track."""
    status = int(msg.status.status)
    if status == STATUS_NO_FIX or (status < 0 and status != STATUS_UNKNOWN):
        return None
    lat, lon = float(msg.latitude), float(msg.longitude)
    (south, north), (west, east) = LATITUDE_RANGE, LONGITUDE_RANGE
    if not _finite(lat, lon) or not (south <= lat <= north and west <= lon <= east):
        return None
    alt = float(msg.altitude)
    accuracy = None
    if int(msg.position_covariance_type) != COVARIANCE_TYPE_UNKNOWN:
        cov = list(msg.position_covariance)
        if len(cov) >= 5 and _finite(cov[0], cov[4]) and cov[0] >= 0 and cov[4] >= 0:
            accuracy = math.sqrt(max(cov[0], cov[4]))
    return {
        "lon": lon,
        "lat": lat,
        "alt": alt if math.isfinite(alt) else None,
        "status": status if status in KNOWN_FIX_STATUSES else 0,
        "accuracy": accuracy,
        "robot_stamp": stamp_to_datetime(msg.header.stamp),
    }


# --- poses ----------------------------------------------------------------------------------


def transform_of(msg_transform, stamp=None) -> Transform:
    t, r = msg_transform.translation, msg_transform.rotation
    return Transform(
        (float(t.x), float(t.y), float(t.z)),
        (float(r.x), float(r.y), float(r.z), float(r.w)),
        stamp_ns(stamp) if stamp is not None else None,
    )


def pose_stamped(msg) -> dict | None:
    p, q = msg.pose.position, msg.pose.orientation
    x, y = float(p.x), float(p.y)
    quat = (float(q.x), float(q.y), float(q.z), float(q.w))
    if not _finite(x, y):
        return None
    yaw = yaw_of(quat) if _finite(*quat) and any(quat) else None
    return {
        "x": x,
        "y": y,
        "yaw": yaw,
        "frame": msg.header.frame_id.lstrip("/"),
        "robot_stamp": stamp_to_datetime(msg.header.stamp),
    }


# --- maps -----------------------------------------------------------------------------------


def grid_geometry(msg) -> dict | None:
    info = msg.info
    o = info.origin
    quat = (o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w)
    width, height, resolution = int(info.width), int(info.height), float(info.resolution)
    values = (resolution, o.position.x, o.position.y, *quat)
    if width <= 0 or height <= 0 or not _finite(*values) or resolution <= 0:
        return None
    return {
        "frame": msg.header.frame_id.lstrip("/") or "map",
        "width": width,
        "height": height,
        "resolution": resolution,
        "origin_x": float(o.position.x),
        "origin_y": float(o.position.y),
        "origin_yaw": yaw_of(quat) if any(quat) else 0.0,
        "robot_stamp": stamp_to_datetime(msg.header.stamp),
    }


def grid_checksum(msg, geometry: dict) -> str:
    h = hashlib.sha256()
    h.update(memoryview(np.ascontiguousarray(np.asarray(msg.data, dtype=np.int8))).cast("B"))
    h.update(repr([geometry[k] for k in MapImage.PLACEMENT_FIELDS]).encode())
    return h.hexdigest()


def grid_is_usable(msg) -> bool:
    geometry = grid_geometry(msg)
    return geometry is not None and len(msg.data) == geometry["width"] * geometry["height"]


def _grid_grey_table() -> np.ndarray:
    values = np.arange(256, dtype=np.uint8).view(np.int8).astype(np.int16)
    grey = np.rint(254 - values * (254 / 100))
    grey[(values < 0) | (values > 100)] = 205
    return grey.astype(np.uint8)


_GRID_GREY = _grid_grey_table()


def grid_to_png(msg) -> bytes:
    """Occupancy grid → greyscale PNG, map_server's colours: free white,
    occupied black, unknown grey, in between shades.  Row 0 of the grid is at
    the origin (bottom), row 0 of an image is the top, hence the flip."""
    width, height = int(msg.info.width), int(msg.info.height)
    cells = np.asarray(msg.data, dtype=np.int8).reshape(height, width).view(np.uint8)
    grey = _GRID_GREY[cells]  # a table lookup: no float copies of a 4-megacell grid
    out = io.BytesIO()
    PilImage.fromarray(grey[::-1], mode="L").save(out, format="PNG", compress_level=1)
    return out.getvalue()


def any_image_to_png(data: bytes) -> bytes:
    with PilImage.open(io.BytesIO(bytes(data))) as img:
        out = io.BytesIO()
        img.convert("L" if img.mode in ("L", "I", "I;16") else "RGB").save(out, format="PNG")
        return out.getvalue()


# --- camera ---------------------------------------------------------------------------------

_CHANNELS = {
    "rgb8": ("u1", 3, "RGB"),
    "bgr8": ("u1", 3, "BGR"),
    "rgba8": ("u1", 4, "RGBA"),
    "bgra8": ("u1", 4, "BGRA"),
    "rgb16": ("u2", 3, "RGB"),
    "bgr16": ("u2", 3, "BGR"),
    "rgba16": ("u2", 4, "RGBA"),
    "bgra16": ("u2", 4, "BGRA"),
    "mono8": ("u1", 1, "L"),
    "mono16": ("u2", 1, "L"),
    "8uc1": ("u1", 1, "L"),
    "8uc3": ("u1", 3, "BGR"),  # OpenCV's default channel order
    "8uc4": ("u1", 4, "BGRA"),
    "16uc1": ("u2", 1, "L"),
    "32fc1": ("f4", 1, "L"),
    "64fc1": ("f8", 1, "L"),
}
# OpenCV names a Bayer pattern after the second row's second and third pixels,
# ROS after the first row's first two: the ROS pattern RGGB is OpenCV's BG.
_BAYER = {"bayer_rggb8": "BG", "bayer_bggr8": "RG", "bayer_gbrg8": "GR", "bayer_grbg8": "GB"}


class UnsupportedImage(ValueError):
    pass


def _to_uint8(a: np.ndarray) -> np.ndarray:
    if a.dtype == np.uint8:
        return a
    a = a.astype(np.float64)
    finite = np.isfinite(a)
    if not finite.any():
        return np.zeros(a.shape, np.uint8)
    lo, hi = float(a[finite].min()), float(a[finite].max())
    # Depth and 16-bit images rarely span the full range: stretch what is there.
    scaled = (a - lo) * (255.0 / (hi - lo)) if hi > lo else np.zeros_like(a)
    return np.nan_to_num(scaled, nan=0.0, posinf=255.0, neginf=0.0).clip(0, 255).astype(np.uint8)


def image_array(msg) -> tuple[np.ndarray, str]:
    """A sensor_msgs/Image as an RGB (or L) uint8 array with correct colours."""
    encoding = msg.encoding.lower()
    width, height, step = int(msg.width), int(msg.height), int(msg.step)
    if width <= 0 or height <= 0:
        raise UnsupportedImage(_("empty image"))
    raw = byte_array(msg.data)
    if encoding in _BAYER or encoding in ("yuv422", "uyvy", "yuyv", "yuv422_yuy2"):
        import cv2

        if step < width * (1 if encoding in _BAYER else 2) or raw.size < step * height:
            raise UnsupportedImage(_("image data shorter than width × height"))
        rows = raw[: step * height].reshape(height, step)
        if encoding in _BAYER:
            code = getattr(cv2, f"COLOR_Bayer{_BAYER[encoding]}2RGB")
            return cv2.cvtColor(np.ascontiguousarray(rows[:, :width]), code), "RGB"
        code = cv2.COLOR_YUV2RGB_UYVY if encoding in ("yuv422", "uyvy") else cv2.COLOR_YUV2RGB_YUY2
        pairs = np.ascontiguousarray(rows[:, : width * 2]).reshape(height, width, 2)
        return cv2.cvtColor(pairs, code), "RGB"
    if encoding not in _CHANNELS:
        raise UnsupportedImage(
            _("unsupported encoding '%(encoding)s'") % {"encoding": msg.encoding}
        )
    kind, channels, order = _CHANNELS[encoding]
    dtype = np.dtype(kind).newbyteorder(">" if msg.is_bigendian else "<")
    row_bytes = width * channels * dtype.itemsize
    if step < row_bytes or raw.size < step * (height - 1) + row_bytes:
        raise UnsupportedImage(_("image data shorter than width × height"))
    padded = np.lib.stride_tricks.as_strided(
        raw, shape=(height, row_bytes), strides=(step, 1), writeable=False
    )
    pixels = np.ascontiguousarray(padded).view(dtype).reshape(height, width, channels)
    pixels = _to_uint8(pixels)
    if order == "L":
        return pixels[:, :, 0], "L"
    if order.startswith("BGR"):
        pixels = pixels[:, :, [2, 1, 0]]
    return np.ascontiguousarray(pixels[:, :, :3]), "RGB"


def image_to_jpeg(msg, max_side: int = 0) -> bytes:
    pixels, mode = image_array(msg)
    img = PilImage.fromarray(pixels, mode=mode)
    if max_side and max(img.size) > max_side:
        img.thumbnail((max_side, max_side))
    out = io.BytesIO()
    img.save(out, format="JPEG", quality=JPEG_QUALITY)
    return out.getvalue()


def compressed_image(msg) -> tuple[bytes, str]:
    """(bytes, file suffix) of a CompressedImage, checked to be a decodable image."""
    data = byte_array(msg.data).tobytes()
    if not data:
        raise UnsupportedImage(_("empty compressed image"))
    fmt = msg.format.lower()
    if "png" in fmt or data.startswith(b"\x89PNG"):
        suffix = "png"
    elif "jpeg" in fmt or "jpg" in fmt or data.startswith(b"\xff\xd8"):
        suffix = "jpg"
    else:
        raise UnsupportedImage(
            _("unsupported compressed format '%(format)s'") % {"format": msg.format}
        )
    try:
        with PilImage.open(io.BytesIO(data)) as img:
            img.verify()
    except Exception as exc:
        raise UnsupportedImage(
            _("undecodable %(kind)s: %(exc)s") % {"kind": suffix, "exc": exc}
        ) from None
    return data, suffix
