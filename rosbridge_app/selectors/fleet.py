"""The fleet: every vehicle logging now, for a test director running several
robots at once (the GUI's fleet view, /gui/api/fleet/)."""

from datetime import timedelta

from django.db.models import OuterRef, Subquery
from django.utils import timezone

from events.models import Segment, SegmentType
from rosbridge_app.selectors.collectors import is_online, logging_into
from telemetry.selectors.tracks import with_last_position

# A collector unheard of for this long was killed or lost for good, though its
# row still says "logging"; until then it is shown, marked offline.
FORGET_AFTER = timedelta(minutes=10)


def fleet(now=None, legs=None) -> list[dict]:
    """One entry per logging vehicle, JSON-ready, in one query however many there are;
    ``legs``: only the vehicles logging into these (the live feed's entries).

    A vehicle with two collectors logging (a restart under a new name) is shown
    once, by the collector heard last."""
    now = now or timezone.now()
    logging = logging_into()
    if legs is not None:
        logging = logging.filter(leg__in=legs)
    masters = Segment.objects.masters()
    open_master = masters.filter(leg=OuterRef("leg"), end__isnull=True)
    # Take-overs of the whole shift: a new leg does not reset the robot's record.
    last_takeover = masters.filter(
        leg__shift=OuterRef("leg__shift"), segment_type=SegmentType.ITO
    ).order_by("-start", "-id")
    rows = with_last_position(
        logging.filter(vehicle__isnull=False, last_seen__gte=now - FORGET_AFTER)
        .select_related("leg__shift__test_event")
        .annotate(
            mode=Subquery(open_master.values("segment_type")[:1]),
            mode_since=Subquery(open_master.values("start")[:1]),
            last_takeover=Subquery(last_takeover.values("start")[:1]),
        )
    )
    result, seen = [], set()
    for c in rows:
        if c.vehicle_id in seen:
            continue
        seen.add(c.vehicle_id)
        leg, shift = c.leg, c.leg.shift
        event = shift.test_event
        result.append(
            {
                "vehicle": {
                    "id": c.vehicle_id,
                    "key": c.vehicle.key,
                    "name": c.vehicle.short_description or c.vehicle.key,
                },
                "collector": {
                    "id": c.pk,
                    "name": c.name,
                    "online": is_online(c, now),
                    "pending": c.pending,
                },
                "leg": {
                    "id": leg.pk,
                    "number": leg.number,
                    "shift": shift.pk,
                    "shift_number": shift.number,
                    "test_event": event.pk,
                    "location": event.location,
                    "time_zone": event.time_zone,
                },
                "mode": c.mode,
                "mode_since": _iso(c.mode_since),
                "last_takeover": _iso(c.last_takeover),
                # [lat, lon]: the order Leaflet takes, as in the leg's tracks.
                "position": None if c.last_lat is None else [c.last_lat, c.last_lon],
            }
        )
    return result


def _iso(value):
    return value.isoformat() if value is not None else None
