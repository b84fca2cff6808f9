"""The original robots' API answers input it cannot read with a 4xx in the
original's shape: JSON nested too deeply, a map whose PNG chunks check but
whose pixels do not inflate."""

import base64
import struct
import zlib

import pytest

from events.services.robots import ensure_robot_account
from telemetry.models import MapImage

pytestmark = pytest.mark.django_db


def png_with_broken_pixels() -> bytes:
    """Every chunk's CRC right, the pixel data no zlib stream."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    header = struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", b"no pixels")
        + chunk(b"IEND", b"")
    )


@pytest.fixture
def robot(leg, vehicle):
    return f"/legacy/{ensure_robot_account('husky-robot', [vehicle]).token}"


def refused(answer):
    assert 400 <= answer.status_code < 500, (answer.status_code, answer.content[:300])
    assert answer.json()["message"].startswith("[ERROR] (")
    return answer.json()["message"]


def test_json_nested_too_deeply_is_refused(client, robot):
    deep = "[" * 100_000 + "]" * 100_000
    for path in ("segment", "pose", "map_image"):
        message = refused(client.post(f"{robot}/{path}", deep, content_type="application/json"))
        assert "nested too deeply" in message


def test_a_map_that_does_not_decode_is_refused(client, robot):
    body = {
        "shift_id": "Current Shift",
        "frame_id": "map",
        "width": 4,
        "height": 4,
        "resolution": 1,
        "origin_x": 0,
        "origin_y": 0,
        "image_data": base64.b64encode(png_with_broken_pixels()).decode(),
    }
    assert "Not a readable" in refused(
        client.post(f"{robot}/map_image", body, content_type="application/json")
    )
    assert not MapImage.objects.exists()
