"""System checks for mistakes an administrator can make in the environment."""

import os
import zoneinfo

from django.conf import settings
from django.core.checks import Error, register


@register()
def media_root_writable(app_configs, **kwargs):
    root = settings.MEDIA_ROOT
    try:
        os.makedirs(root, exist_ok=True)
    except OSError as exc:
        return [Error(f"Cannot create MEDIA_ROOT {root}: {exc}", id="ftt.E001")]
    if not os.access(root, os.W_OK):
        return [
            Error(
                f"MEDIA_ROOT {root} is not writable; images and maps could not be stored.",
                hint="Fix the permissions or point FTT_MEDIA_ROOT elsewhere.",
                id="ftt.E002",
            )
        ]
    return []


@register()
def default_time_zone_known(app_configs, **kwargs):
    if settings.TIME_ZONE not in zoneinfo.available_timezones():
        return [
            Error(
                f"FTT_TIME_ZONE {settings.TIME_ZONE!r} is not an IANA name.",
                id="ftt.E003",
            )
        ]
    return []
