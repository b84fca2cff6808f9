"""The fields of the original's request bodies, checked one by one.

The node sends JSON whatever its Content-Type says; a missing, mistyped or
unreadable field is refused with a message that names it (the original
answered 500 for most of these).
"""

import base64
import binascii
import json
import math
from datetime import UTC, datetime

from rosbridge_app.legacy_api.answers import LegacyRefusal

# The magic ids the original resolves to the open entry of its level.
CURRENT_LEG = "Current Leg"
CURRENT_SHIFT = "Current Shift"
CURRENT_SEGMENT = "Current Segment"


def body_of(request) -> dict:
    try:
        data = json.loads(request.body or b"{}")
    except (ValueError, UnicodeDecodeError):
        raise LegacyRefusal("KeyValueError", "The body is not JSON.") from None
    except RecursionError:
        raise LegacyRefusal("KeyValueError", "The body is JSON nested too deeply.") from None
    if not isinstance(data, dict):
        raise LegacyRefusal("KeyValueError", "The body must be a JSON object.")
    return data


def required(data: dict, *names: str) -> None:
    missing = [name for name in names if name not in data]
    if missing:
        raise LegacyRefusal("KeyError", f"Missing field(s): {', '.join(missing)}.")


def entry_id(data: dict, name: str, current: str) -> int | None:
    """The row id in ``name``, or None for the magic ``current`` name."""
    value = data.get(name)
    if value == current:
        return None
    if isinstance(value, int) and not isinstance(value, bool) and value > 0:
        return value
    if isinstance(value, str) and value.isascii() and value.isdigit():
        return int(value)
    raise LegacyRefusal("KeyValueError", f"{name} must be a positive integer or '{current}'.")


def number(data: dict, name: str, *, optional: bool = False) -> float | None:
    value = data.get(name)
    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise LegacyRefusal("KeyValueError", f"{name} must be a finite number.")
    return float(value)


def whole(data: dict, name: str) -> int:
    value = data.get(name)
    if isinstance(value, bool) or not isinstance(value, int):
        raise LegacyRefusal("KeyValueError", f"{name} must be an integer.")
    return value


def text(data: dict, name: str, *, limit: int = 200) -> str:
    value = data.get(name)
    if value is None:
        return ""
    if not isinstance(value, str):
        raise LegacyRefusal("KeyValueError", f"{name} must be text.")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise LegacyRefusal("KeyValueError", f"{name} is not valid Unicode text.") from None
    return value[:limit]


def robot_time(data: dict, name: str) -> datetime | None:
    """The robot's clock (seconds since 1970), or None when the node sent none."""
    seconds = number(data, name, optional=True)
    if seconds is None:
        return None
    try:
        return datetime.fromtimestamp(seconds, UTC)
    except (OverflowError, OSError, ValueError):
        raise LegacyRefusal("KeyValueError", f"{name} is not a time.") from None


def picture(data: dict, name: str) -> bytes:
    """The base64 text of a JPEG the node sends."""
    value = data.get(name)
    if not isinstance(value, str) or not value:
        raise LegacyRefusal("KeyValueError", f"{name} must be base64 text of a picture.")
    try:
        return base64.b64decode(value, validate=True)
    except (binascii.Error, ValueError):
        raise LegacyRefusal("KeyValueError", f"{name} is not base64 text.") from None
