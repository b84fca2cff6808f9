"""Turning the original's column values into archive record values."""

import base64
import binascii
import re
import uuid
import zoneinfo
from datetime import UTC, datetime

from django.contrib.gis.geos import GEOSException, GEOSGeometry
from django.utils.text import slugify
from django.utils.translation import gettext

from exchange.legacy.sources import LegacyError


def to_float(value) -> float | None:
    return None if value is None else float(value)


def to_int(value) -> int | None:
    return None if value is None else int(value)


def to_time(secs) -> datetime | None:
    return None if secs is None else datetime.fromtimestamp(float(secs), tz=UTC)


def to_text(value) -> str:
    return "" if value is None else str(value)


def fit(value, model, field_name: str) -> str:
    """The original's columns (varchar(512)) are wider than ours; the limit comes
    from the model so that the cut follows it if the model's limit changes."""
    return to_text(value)[: model._meta.get_field(field_name).max_length]


def point_xy(ewkb) -> tuple[float, float] | None:
    if ewkb is None:
        return None
    try:
        point = GEOSGeometry(ewkb.hex() if isinstance(ewkb, bytes) else ewkb)
    except (GEOSException, ValueError, TypeError):
        raise LegacyError(
            gettext("Unreadable geometry value %(value)s.") % {"value": repr(str(ewkb)[:40])}
        ) from None
    return point.x, point.y


def derived_uid(parent: uuid.UUID, *parts) -> str:
    return str(uuid.uuid5(parent, ":".join(repr(p) for p in parts)))


def iana_zone(label: str | None) -> str:
    """The original GUI stored labels such as "(UTC+01:00)"; FTT needs IANA names."""
    label = (label or "").strip()
    if label in zoneinfo.available_timezones():
        return label
    match = re.search(r"UTC\s*([+-])(\d{1,2}):?(\d{2})?", label)
    if match and (match.group(3) in (None, "00")):
        hours = int(match.group(2))
        if hours == 0:
            return "UTC"
        # POSIX sign convention: Etc/GMT-1 is one hour ahead of UTC.
        sign = "-" if match.group(1) == "+" else "+"
        return f"Etc/GMT{sign}{hours}"
    return "UTC"


def catalogue_key(value, fallback: str, model) -> str:
    return fit(slugify(value or ""), model, "key") or fallback


def rgb_colour(value, fallback="128,128,128") -> str:
    value = re.sub(r"\s", "", value or "")
    return value if re.fullmatch(r"\d{1,3},\d{1,3},\d{1,3}", value) else fallback


def decode_picture(data: bytes) -> bytes:
    """Images were stored as the base64 text the client sent, inside bytea."""
    if data.startswith((b"\xff\xd8\xff", b"\x89PNG")):
        return data  # already a picture (written by some other tool)
    try:
        return base64.b64decode(data, validate=False)
    except (binascii.Error, ValueError):
        return data
