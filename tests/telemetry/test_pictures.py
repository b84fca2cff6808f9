"""Photos are JPEG, PNG or WebP and maps PNG, decoded, whatever the upload's name says."""

import io

import pytest
from django.core.exceptions import ValidationError
from django.core.files.uploadedfile import SimpleUploadedFile
from PIL import Image as PilImage

from telemetry.models import Image, MapImage
from telemetry.pictures import MAP_FORMATS, checked_picture
from tests.support.images import image_bytes
from tests.support.modes import start_auto

pytestmark = pytest.mark.django_db


def _eps() -> bytes:
    out = io.BytesIO()
    PilImage.new("RGB", (4, 4)).save(out, format="EPS")
    return out.getvalue()


@pytest.fixture
def post_photo(api_client, leg, media_root):
    client = api_client("operator")
    master = start_auto(leg)

    def send(name: str, content: bytes):
        upload = SimpleUploadedFile(name, content, "image/jpeg")
        return client.post(
            "/api/images/", {"segment": master.pk, "image": upload}, format="multipart"
        )

    return send


def test_a_webp_photo_is_stored_under_its_own_extension(post_photo, media_root):
    response = post_photo("photo.jpg", image_bytes(fmt="WEBP"))
    assert response.status_code == 201, response.json()
    assert Image.objects.get().image.name.endswith(".webp")
    assert response.json()["image"].endswith(".webp")


@pytest.mark.parametrize(
    "content",
    [_eps(), image_bytes(fmt="GIF"), image_bytes(fmt="BMP")],
    ids=["eps", "gif", "bmp"],
)
def test_other_picture_formats_are_refused_as_photos(post_photo, content):
    response = post_photo("photo.jpg", content)
    assert response.status_code == 400
    assert "JPEG/PNG/WEBP" in str(response.json()["errors"]["image"])
    assert not Image.objects.exists()


def test_a_decompression_bomb_is_refused(post_photo, settings):
    settings.FTT_MAX_IMAGE_PIXELS = 100
    response = post_photo("big.png", image_bytes(size=(20, 20)))
    assert response.status_code == 400
    assert "more than 100 pixels" in str(response.json()["errors"]["image"])
    assert not Image.objects.exists()


def test_maps_are_png_only_also_on_the_service_path(shift, media_root):
    from django.core.exceptions import ValidationError

    from telemetry.services import map_images

    with pytest.raises(ValidationError, match="PNG"):
        map_images.store_map(
            shift,
            png=image_bytes(fmt="WEBP"),
            frame="map",
            width=4,
            height=3,
            resolution=0.1,
            origin_x=0,
            origin_y=0,
        )
    assert not MapImage.objects.exists()


def _damaged_pngs() -> dict[str, bytes]:
    png = image_bytes(fmt="PNG", size=(64, 64))
    data = png.index(b"IDAT") + 8
    flipped = png[:data] + bytes([png[data] ^ 0xFF]) + png[data + 1 :]
    return {"truncated": png[: len(png) // 2], "flipped pixel byte": flipped}


@pytest.mark.parametrize("name", ["truncated", "flipped pixel byte"])
def test_a_damaged_png_map_is_refused(name):
    # What the collector and the importers call (the API's form checks uploads first).
    with pytest.raises(ValidationError, match="Not a readable PNG"):
        checked_picture(_damaged_pngs()[name], MAP_FORMATS)
    assert checked_picture(image_bytes(fmt="PNG", size=(64, 64)), MAP_FORMATS) == "png"
