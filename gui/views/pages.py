"""The operator GUI: one page whose script talks to /api/ and to ws/live/.

The page itself only carries what the script cannot ask the API for: who is
logged in, which role they have and the site's map settings.
"""

import functools
import re

from django.conf import settings
from django.contrib.auth.decorators import login_required
from django.contrib.staticfiles import finders
from django.shortcuts import redirect, render
from django.templatetags.static import static
from django.urls import reverse

from common import roles
from events.models import ItoReason, Performer, PoseSource, Vehicle
from rosbridge_app.selectors.collectors import logging_into


def missing_configuration() -> list[str]:
    """What an administrator must add before the first shift can start."""
    checks = (
        (Performer, "a performer", "admin:events_performer_add"),
        (Vehicle, "a vehicle", "admin:events_vehicle_add"),
        (PoseSource, "a pose source", "admin:events_posesource_add"),
    )
    missing = []
    for model, label, url_name in checks:
        if not model.objects.exists():
            try:
                url = reverse(url_name)
            except Exception:  # noqa: BLE001 - admin not registered yet: plain text
                url = ""
            missing.append({"label": label, "url": url})
    return missing


def logged_leg() -> dict | None:
    """The leg a collector is logging into, offered when the address names none."""
    collector = logging_into().first()
    if collector is None:
        return None
    leg = collector.leg
    return {"event": leg.shift.test_event_id, "shift": leg.shift_id, "leg": leg.pk}


# `import ... from "./x.js"`, `export ... from "./x.js"` and `import "./x.js"`.
_IMPORT = re.compile(r'^(?:import|export)\b[^;]*?(?:from\s+)?"\./([\w-]+\.js)"', re.M)


@functools.cache
def module_graph(entry: str) -> tuple[str, ...]:
    """Every module ``entry`` (a static path such as "gui/main.js") imports,
    directly or not, read from the modules' own import lines.  The page lists
    them as modulepreload links, so the browser fetches them all at once instead
    of discovering them level by level, one round trip each."""
    folder = entry.rsplit("/", 1)[0]
    found, todo = [], [entry]
    while todo:
        path = finders.find(todo.pop())
        if path is None:
            continue
        with open(path, encoding="utf-8") as source:
            for match in _IMPORT.finditer(source.read()):
                name = f"{folder}/{match.group(1)}"
                if name not in found and name != entry:
                    found.append(name)
                    todo.append(name)
    return tuple(found)


@login_required
def index(request):
    user = request.user
    is_admin = roles.has_role(user, roles.ADMINISTRATOR)
    personnel = getattr(user, "personnel", None)
    context = {
        "can_view": roles.has_role(user, roles.VIEWER),
        "can_operate": roles.has_role(user, roles.OPERATOR),
        "is_admin": is_admin,
        "missing": missing_configuration() if is_admin else [],
        "levels": [("event", "Test event"), ("shift", "Shift"), ("leg", "Leg")],
        # The catalogue says which reasons get a button (ItoReason.quick, set in admin).
        "quick_reasons": ItoReason.objects.filter(quick=True).order_by("short_description"),
        "modules": module_graph("gui/main.js"),
        "gui_config": {
            "tileUrl": settings.FTT_TILE_URL,
            "tileAttribution": getattr(settings, "FTT_TILE_ATTRIBUTION", ""),
            "canOperate": roles.has_role(user, roles.OPERATOR),
            "isAdmin": is_admin,
            "user": user.get_full_name() or user.get_username(),
            "personnel": personnel.pk if personnel else None,
            "loggingLeg": logged_leg(),
            "wsPath": "/ws/live/",
            "apiRoot": "/api/",
            "guiApiRoot": "/gui/api/",
        },
    }
    return render(request, "gui/index.html", context)


@login_required
def compare(request):
    """Reliability of several test events side by side; the script asks
    /api/reports/compare/ for the figures and /api/reports/ for the PDF."""
    user = request.user
    context = {
        "can_view": roles.has_role(user, roles.VIEWER),
        "gui_config": {
            "canOperate": roles.has_role(user, roles.OPERATOR),
            "apiRoot": "/api/",
        },
    }
    return render(request, "gui/compare.html", context)


def favicon(request):
    # Browsers ask for /favicon.ico whatever the page links; the icon is a static SVG.
    return redirect(static("gui/favicon.svg"), permanent=True)
