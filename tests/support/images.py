"""Small images for uploads, recordings and archives."""

import io

from django.core.files.uploadedfile import SimpleUploadedFile
from PIL import Image as PILImage


def image_bytes(size=(4, 3), colour=(10, 200, 30), fmt="PNG", mode="RGB") -> bytes:
    buffer = io.BytesIO()
    PILImage.new(mode, size, colour).save(buffer, format=fmt)
    return buffer.getvalue()


def png(size=(4, 3), colour=(10, 200, 30), fmt="PNG") -> bytes:
    return image_bytes(size, colour, fmt)


def grey_png(level: int, size=(8, 6)) -> bytes:
    return image_bytes(size, level, "PNG", mode="L")


def jpeg(colour: int, size=(16, 12)) -> bytes:
    """A JPEG whose red channel is ``colour``, so frames are told apart."""
    return image_bytes(size, (colour, 10, 200), "JPEG")


def upload(name="map.png", fmt="PNG", **kwargs) -> SimpleUploadedFile:
    content_type = "image/png" if fmt == "PNG" else "image/jpeg"
    return SimpleUploadedFile(name, png(fmt=fmt, **kwargs), content_type=content_type)


# The smallest valid PNG (1×1, transparent), for tests that only need "a file".
PNG = image_bytes((1, 1), (0, 0, 0, 0), "PNG", mode="RGBA")


def map_form(shift, **fields) -> dict:
    """The multipart form of a 4 x 3 map for ``shift`` (``POST /api/maps/``)."""
    return {
        "shift": shift.pk,
        "frame": "map",
        "width": 4,
        "height": 3,
        "resolution": 0.05,
        "origin_x": 0,
        "origin_y": 0,
        "image": upload(),
        **fields,
    }
