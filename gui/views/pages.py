"""The operator GUI: one page whose script talks to /api/ and to ws/live/.

The page carries what the script cannot ask the API for: who is logged in,
which role they have and the site's map settings; and, so that the first screen
does not wait for a chain of requests, the answers of the script's first reads.
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
from events import feed
from events.api import serializers as s
from events.models import ItoReason, Leg, Performer, PoseSource, Shift, TestEvent, Vehicle
from gui.views.gui_api import leg_segments, read_ahead
from rosbridge_app.selectors.collectors import logging_into

# How static/gui/api.js's list() asks for a whole list.
WHOLE_LIST = "?page_size=5000"


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


def _chosen(request, name: str) -> int | None:
    value = request.GET.get(name, "")
    return int(value) if value.isdigit() else None


def first_answers(request, logging: dict | None) -> dict[str, object]:
    """{URL the page's script reads first: its answer}: the catalogues, the pickers
    down to the leg in the address (or the leg a collector logs into) and that leg's
    segments, each as its REST or /gui/api/ read answers it.  The script takes each
    once instead of asking (static/gui/api.js); later reads go to the server.
    That leg's tracks are read ahead meanwhile (``read_ahead``): the script asks
    for them as its modules load."""
    chosen = {k: _chosen(request, k) for k in ("event", "shift", "leg")}
    if chosen["event"] is None and logging:
        chosen = logging
    context = {"request": request}

    def rows(serializer, queryset):
        data = serializer(queryset, many=True, context=context).data
        # One page, as common.api.pagination answers WHOLE_LIST (lists are far shorter).
        return {"count": len(data), "next": None, "previous": None, "results": data}

    answers = {
        "/api/ito-reasons/" + WHOLE_LIST: s.ItoReasonSerializer(
            ItoReason.objects.all(), many=True, context=context
        ).data,
        "/api/vehicles/" + WHOLE_LIST: rows(s.VehicleSerializer, Vehicle.objects.all()),
        "/api/test-events/" + WHOLE_LIST: rows(s.TestEventSerializer, TestEvent.objects.all()),
    }
    event, shift, leg = chosen["event"], chosen["shift"], chosen["leg"]
    if event is not None:
        shifts = Shift.objects.filter(test_event_id=event)
        answers[f"/api/shifts/{WHOLE_LIST}&test_event={event}"] = rows(s.ShiftSerializer, shifts)
    if shift is not None:
        legs = list(Leg.objects.select_related("shift").filter(shift_id=shift))
        answers[f"/api/legs/{WHOLE_LIST}&shift={shift}"] = rows(s.LegSerializer, legs)
        shown = next((r for r in legs if r.pk == leg), None)
        if shown is not None:
            answers[f"/gui/api/legs/{leg}/segments/"] = leg_segments(shown)
            read_ahead(shown)
    return answers


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
    logging = logged_leg()
    can_view = roles.has_role(user, roles.VIEWER)
    # Before the answers are read: what is announced meanwhile reaches the page live.
    last_event = feed.bounds()[1]
    context = {
        "can_view": can_view,
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
            "loggingLeg": logging,
            "wsPath": "/ws/live/",
            "apiRoot": "/api/",
            "guiApiRoot": "/gui/api/",
            "lastEventId": last_event,
            "answers": first_answers(request, logging) if can_view else {},
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
