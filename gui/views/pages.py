"""The operator GUI: one page whose script talks to /api/ and to ws/live/.

The page carries what the script cannot ask the API for: who is logged in,
which role they have and the site's map settings; and, so that the first screen
does not wait for a chain of requests, what the script reads first (``bootstrap``).
"""

import functools
import re

from django.conf import settings
from django.contrib.auth.decorators import login_required
from django.contrib.staticfiles import finders
from django.http import HttpResponse
from django.shortcuts import redirect, render
from django.templatetags.static import static
from django.urls import reverse
from django.utils.translation import gettext as _

from common import roles
from common.api.pagination import Pagination
from events import feed
from events.api import serializers as s
from events.models import (
    ItoReason,
    Leg,
    Performer,
    PoseSource,
    Segment,
    Shift,
    TestEvent,
    Vehicle,
)
from gui.views.gui_api import leg_segments, read_ahead
from rosbridge_app.selectors.collectors import is_online, logging_into
from rosbridge_app.selectors.fleet import fleet


def missing_configuration() -> list[str]:
    """What an administrator must add before the first shift can start."""
    checks = (
        (Performer, _("a performer"), "admin:events_performer_add"),
        (Vehicle, _("a vehicle"), "admin:events_vehicle_add"),
        (PoseSource, _("a pose source"), "admin:events_posesource_add"),
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


# The cookie the cockpit keeps with what it shows ("event.shift.leg"), so that a
# bare address opens it again in this browser.
LAST_COCKPIT = "ftt_cockpit"


def opening(request) -> dict | None:
    """What a bare address opens: the cockpit this browser showed last while its leg
    still exists; else the one leg collectors log into; with robots logging into
    several legs, the fleet view, which asks the operator to pick one."""
    last = request.COOKIES.get(LAST_COCKPIT, "").split(".")
    if len(last) == 3 and all(part.isdigit() for part in last):
        event, shift, leg = map(int, last)
        if Leg.objects.filter(pk=leg, shift_id=shift, shift__test_event_id=event).exists():
            return {"event": event, "shift": shift, "leg": leg}
    legs = {c.leg for c in logging_into() if is_online(c)}
    if len(legs) > 1:
        return {"view": "fleet"}
    if not legs:
        return None
    (leg,) = legs
    return {"event": leg.shift.test_event_id, "shift": leg.shift_id, "leg": leg.pk}


def _chosen(request, name: str) -> int | None:
    value = request.GET.get(name, "")
    return int(value) if value.isdigit() else None


def bootstrap(request, opened: dict | None) -> dict[str, dict]:
    """What the cockpit's script reads first, named by what it is: the catalogues,
    the rows of each picker down to the leg in the address (or the one a bare
    address opens) and that leg's segments, as /api/ and /gui/api/ answer them;
    on the fleet view, the fleet (one query), drawn as soon as the script runs.

    Each piece is ``{"of": the parent's id or None, "data": ...}``; the script
    takes a piece once, when it reads that very thing (static/gui/bootstrap.js),
    and asks the server for everything after.  That leg's tracks are read ahead
    meanwhile (``read_ahead``): the script asks for them as its modules load."""
    chosen = {k: _chosen(request, k) for k in ("event", "shift", "leg")}
    if chosen["event"] is None and opened and "leg" in opened:
        chosen = opened
    context = {"request": request}

    def piece(data, of=None):
        return {"of": of, "data": data}

    def rows(serializer, queryset):
        return serializer(queryset, many=True, context=context).data

    pieces = {
        "reasons": piece(rows(s.ItoReasonSerializer, ItoReason.objects.all())),
        "vehicles": piece(rows(s.VehicleSerializer, Vehicle.objects.all())),
        "event": piece(rows(s.TestEventSerializer, TestEvent.objects.all())),
    }
    if request.GET.get("view") == "fleet" or (opened or {}).get("view") == "fleet":
        pieces["fleet"] = piece({"vehicles": fleet()})
    event, shift, leg = chosen["event"], chosen["shift"], chosen["leg"]
    if event is not None:
        shifts = Shift.objects.filter(test_event_id=event)
        pieces["shift"] = piece(rows(s.ShiftSerializer, shifts), event)
    if shift is not None:
        legs = list(Leg.objects.select_related("shift").filter(shift_id=shift))
        pieces["leg"] = piece(rows(s.LegSerializer, legs), shift)
        shown = next((r for r in legs if r.pk == leg), None)
        if shown is not None:
            pieces["segments"] = piece(leg_segments(shown), leg)
            read_ahead(shown)
    return pieces


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
    opened = None if request.GET else opening(request)
    can_view = roles.has_role(user, roles.VIEWER)
    # Before the answers are read: what is announced meanwhile reaches the page live.
    last_event = feed.bounds()[1]
    context = {
        "can_view": can_view,
        "can_operate": roles.has_role(user, roles.OPERATOR),
        "is_admin": is_admin,
        "missing": missing_configuration() if is_admin else [],
        "levels": [("event", _("Test event")), ("shift", _("Shift")), ("leg", _("Leg"))],
        # The catalogue says which reasons get a button (ItoReason.quick, set in admin).
        "quick_reasons": ItoReason.objects.filter(quick=True).order_by("short_description"),
        # A take-over's regulator fields (segment dialog).
        "initiators": Segment.INITIATORS,
        "severities": Segment.SEVERITIES,
        "location_types": settings.FTT_LOCATION_TYPES,
        "modules": module_graph("gui/main.js"),
        "gui_config": {
            "tileUrl": settings.FTT_TILE_URL,
            "tileAttribution": getattr(settings, "FTT_TILE_ATTRIBUTION", ""),
            "canOperate": roles.has_role(user, roles.OPERATOR),
            # A take-over reason's fields and what a new reason holds (the segment dialog).
            "annotation": Segment.NO_ANNOTATION,
            "isAdmin": is_admin,
            "user": user.get_full_name() or user.get_username(),
            # Whose writes this browser keeps offline (outbox.js): only theirs are sent.
            "account": user.pk,
            "personnel": personnel.pk if personnel else None,
            "opening": opened,
            "cockpitCookie": LAST_COCKPIT,
            "wsPath": "/ws/live/",
            "apiRoot": "/api/",
            "guiApiRoot": "/gui/api/",
            "lastEventId": last_event,
            # The longest page /api/ lists answer: the script asks for whole lists.
            "pageSize": Pagination.max_page_size,
            "bootstrap": bootstrap(request, opened) if can_view else {},
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
            "guiApiRoot": "/gui/api/",
            "pageSize": Pagination.max_page_size,
            # The search and route maps draw on the same tiles as the cockpit.
            "tileUrl": settings.FTT_TILE_URL,
            "tileAttribution": getattr(settings, "FTT_TILE_ATTRIBUTION", ""),
        },
    }
    return render(request, "gui/compare.html", context)


def service_worker(request):
    """static/gui/sw.js from the site's root: a service worker controls only the
    addresses under its own, and the cockpit is ``/``."""
    path = finders.find("gui/sw.js")
    with open(path, encoding="utf-8") as source:
        response = HttpResponse(source.read(), content_type="text/javascript")
    # The browser checks for a new worker on each visit; no stale copy in between.
    response["Cache-Control"] = "no-cache"
    return response


def favicon(request):
    # Browsers ask for /favicon.ico whatever the page links; the icon is a static SVG.
    return redirect(static("gui/favicon.svg"), permanent=True)
