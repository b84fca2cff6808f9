"""Robot data on the open leg of the shared fixtures."""

import io

import pytest
from django.core.files.uploadedfile import SimpleUploadedFile
from PIL import Image as PILImage

from events.models import SegmentType
from events.services import segments


def png(size=(4, 3), colour=(10, 200, 30), fmt="PNG") -> bytes:
    buffer = io.BytesIO()
    PILImage.new("RGB", size, colour).save(buffer, format=fmt)
    return buffer.getvalue()


def upload(name="map.png", fmt="PNG", **kwargs) -> SimpleUploadedFile:
    content_type = "image/png" if fmt == "PNG" else "image/jpeg"
    return SimpleUploadedFile(name, png(fmt=fmt, **kwargs), content_type=content_type)


@pytest.fixture
def auto_master(leg):
    return segments.report_mode(leg, SegmentType.AUTO).master
