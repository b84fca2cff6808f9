"""What a stored picture may be, whoever stores it (API, collector, imports).

A file's name or declared type says nothing: only what Pillow reads counts,
and the stored file gets the extension of the format found.  Other formats
are refused because browsers and the report treat them differently (an
``.html`` "photo" would be served as a page; EPS goes to Ghostscript).
"""

import io
import warnings

from django.conf import settings
from django.core.exceptions import ValidationError
from django.utils.translation import gettext as _
from PIL import Image as PilImage

PHOTO_FORMATS = {"JPEG": "jpg", "PNG": "png", "WEBP": "webp"}
# What a map is stored as and accepted as (API, collector, archives): store_map checks it.
MAP_FORMATS = {"PNG": "png"}
# What the original robots' node API may send a map as; it is stored as a greyscale PNG.
LEGACY_MAP_FORMATS = PHOTO_FORMATS


# What Pillow raises on a file it cannot read or decode.
UNREADABLE = (OSError, SyntaxError, ValueError, EOFError, PilImage.DecompressionBombError, KeyError)


def _unreadable(formats: dict[str, str]) -> ValidationError:
    message = _("Not a readable %(kinds)s image.") % {"kinds": "/".join(formats)}
    return ValidationError({"image": [message]})


def checked_picture(content: bytes, formats: dict[str, str] = PHOTO_FORMATS) -> str:
    """The extension to store ``content`` under; ValidationError unless it is one of
    ``formats`` within FTT_MAX_IMAGE_PIXELS, whole (a PNG's chunks check, others decode)."""
    limit = settings.FTT_MAX_IMAGE_PIXELS
    try:
        with warnings.catch_warnings():
            # Our own pixel limit answers first; Pillow's warning would only add noise.
            warnings.simplefilter("ignore", PilImage.DecompressionBombWarning)
            with PilImage.open(io.BytesIO(content), formats=list(formats)) as picture:
                if picture.width * picture.height > limit:
                    message = _("The image has more than %(limit)s pixels.") % {"limit": limit}
                    raise ValidationError({"image": [message]})
                if picture.format == "PNG":
                    # Every chunk's CRC, the pixel data's included, and the end
                    # marker: a truncated or damaged file is refused without
                    # inflating it, which would dominate an outage spool's replay.
                    picture.verify()
                else:
                    picture.load()
                return formats[picture.format]
    except ValidationError:
        raise
    except UNREADABLE:
        raise _unreadable(formats) from None


def greyscale_png(content: bytes) -> bytes:
    """A photo-format picture as the greyscale PNG a map is kept as (the original FTT
    sent and stored its maps as greyscale JPEG)."""
    checked_picture(content, LEGACY_MAP_FORMATS)
    try:
        with PilImage.open(io.BytesIO(content)) as picture:
            out = io.BytesIO()
            picture.convert("L").save(out, format="PNG")
            return out.getvalue()
    except UNREADABLE:
        # A PNG's chunks may check while its pixel data does not inflate.
        raise _unreadable(LEGACY_MAP_FORMATS) from None
