"""The segment state machine, scoped to one leg.

A master segment is one continuous run in one mode (ITO or AUTO, or UNKNOWN
for what the collector logged before the robot said its mode).  An ITO
master always has at least one child; children carry the take-over reason and
its context.  Every change of mode, from the robot or from an operator, goes
through :func:`report_mode` or :func:`new_manual_segment`.
"""

import math
from dataclasses import dataclass
from datetime import datetime

from django.contrib.gis.geos import Point
from django.db import transaction
from django.db.models import Value
from django.db.models.functions import Greatest
from django.utils import timezone
from django.utils.translation import gettext as _

from common.errors import NotFound, RuleViolation
from common.retries import stored_row
from events import rules
from events.feed import announce_and_return
from events.history import write_history
from events.models import ItoReason, Leg, Segment, SegmentType
from events.services.common import (
    apply_fields,
    instant,
    lock,
    require_not_before,
    require_open,
)
from events.services.finality import require_amendable

MODES = (SegmentType.ITO, SegmentType.AUTO, SegmentType.UNKNOWN)


# The coordinates every stored position keeps to, in degrees (WGS 84); every
# check of a sent position (API serializers, batch model, services) reads these.
LONGITUDE_RANGE = (-180, 180)
LATITUDE_RANGE = (-90, 90)


def _label(name: str) -> str:
    return {"longitude": _("Longitude"), "latitude": _("Latitude")}[name]


def _within(value, bounds) -> bool:
    # A float in range (inf is not, NaN compares false); anything else is
    # left to the full check.
    return type(value) is float and bounds[0] <= value <= bounds[1]


@dataclass(frozen=True)
class GpsPosition:
    longitude: float
    latitude: float

    @staticmethod
    def check(longitude, latitude) -> None:
        """The rule, also without building a position: it runs per stored pose,
        and only a position it does not pass at once is checked field by field
        (the messages)."""
        if _within(longitude, LONGITUDE_RANGE) and _within(latitude, LATITUDE_RANGE):
            return
        errors = {}
        for name, value, (low, high) in (
            ("longitude", longitude, LONGITUDE_RANGE),
            ("latitude", latitude, LATITUDE_RANGE),
        ):
            # Labels are translated only for a message: this check runs per stored pose.
            if not (isinstance(value, int | float) and math.isfinite(value)):
                errors[name] = [_("%(name)s must be a finite number.") % {"name": _label(name)}]
            elif not low <= value <= high:
                errors[name] = [
                    _("%(name)s must be between %(low)s and %(high)s degrees.")
                    % {"name": _label(name), "low": f"{low:g}", "high": f"{high:g}"}
                ]
        if errors:
            raise RuleViolation(errors)

    def __post_init__(self):
        self.check(self.longitude, self.latitude)

    def as_point(self) -> Point:
        return Point(self.longitude, self.latitude, srid=4326)


@dataclass(frozen=True)
class LocalPosition:
    x: float
    y: float
    frame: str = ""

    def __post_init__(self):
        for name in ("x", "y"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise RuleViolation(
                    {f"local_{name}": [_("Local coordinates must be finite numbers.")]}
                )


@dataclass(frozen=True)
class ModeReport:
    """What :func:`report_mode` did: the master now open and whether it is new."""

    master: Segment
    changed: bool


def _position_fields(gps: GpsPosition | None, local: LocalPosition | None) -> dict:
    # `is None`, never truthiness: 0.0 is a real coordinate.
    return {
        "start_position": gps.as_point() if gps is not None else None,
        "start_local_x": local.x if local is not None else None,
        "start_local_y": local.y if local is not None else None,
        "start_local_frame": local.frame if local is not None else "",
    }


def _reason(key: str) -> ItoReason:
    try:
        return ItoReason.objects.get(pk=key)
    except ItoReason.DoesNotExist:
        raise RuleViolation(
            {"ito_reason": [_("Unknown ITO reason '%(key)s'.") % {"key": key}]}
        ) from None


def _lock_with_leg(segment: Segment) -> Segment:
    # Leg before segment is the order every writer takes, so closing a leg
    # waits for (or is waited on by) additions to its segments: no deadlock,
    # and no segment opened under a leg that has just been closed.
    Leg.objects.select_for_update(no_key=True).filter(pk=segment.leg_id).first()
    return lock(segment)


def _open_master(leg: Leg) -> Segment | None:
    return rules.open_masters_of_leg(leg.pk).select_for_update(no_key=True).first()


def _open_master_and_reasons(leg: Leg) -> tuple[Segment | None, list[Segment]]:
    rows = list(rules.open_segments_of_leg(leg.pk).select_for_update(no_key=True))
    master = next((row for row in rows if row.parent_id is None), None)
    return master, [row for row in rows if master and row.parent_id == master.pk]


def _end(segment: Segment, at: datetime, reasons: list[Segment] | None = None) -> list[Segment]:
    """End ``segment`` and, for a master, its open ``reasons`` (read here when not
    given) in one write; returns the rows ended, whose history the caller writes."""
    end = max(at, segment.start)
    ending = [segment]
    if segment.parent_id is None:
        ending += segment.children.filter(end__isnull=True) if reasons is None else reasons
    now = timezone.now()
    for row in ending:
        row.end = max(end, row.start)
        row.modified = now
    # A reason that started after ``end`` ends at its start, as the loop above says.
    Segment.objects.filter(pk__in=[row.pk for row in ending]).update(
        end=Greatest("start", Value(end)), modified=now
    )
    return ending


def _close(segment: Segment, at: datetime, reasons: list[Segment] | None = None) -> None:
    write_history(Segment, changed=_end(segment, at, reasons))


def _start_master(
    leg,
    mode,
    at,
    robot_stamp,
    positions,
    reason_key,
    uid,
    start_uncertainty=None,
    reason_uid=None,
    suggested_reason=None,
) -> list[Segment]:
    """The new master and, for ITO, its first reason; the caller writes their history."""
    master = Segment(
        leg=leg,
        segment_type_id=mode,
        start=at,
        robot_stamp=robot_stamp,
        start_uncertainty=start_uncertainty,
        **positions,
    )
    if uid is not None:
        master.uid = uid
    master.save_without_historical_record()
    if mode != SegmentType.ITO:
        return [master]
    child = _new_child(
        master, _reason(reason_key), at, robot_stamp, start_uncertainty, uid=reason_uid
    )
    if suggested_reason:
        # The robot's reason, waiting for the operator's confirmation; a key
        # the catalogue does not have is no suggestion.
        child.suggested_reason = ItoReason.objects.filter(pk=suggested_reason).first()
    child.save_without_historical_record()
    return [master, child]


def _new_child(
    master: Segment,
    reason: ItoReason,
    at: datetime,
    robot_stamp=None,
    start_uncertainty=None,
    uid=None,
) -> Segment:
    return Segment(
        # A uid of None would be stored as NULL instead of the model's default.
        **({} if uid is None else {"uid": uid}),
        start_uncertainty=start_uncertainty,
        leg_id=master.leg_id,
        parent=master,
        segment_type_id=SegmentType.ITO,
        ito_reason=reason,
        start=at,
        robot_stamp=robot_stamp,
        start_position=master.start_position if at == master.start else None,
        start_local_x=master.start_local_x if at == master.start else None,
        start_local_y=master.start_local_y if at == master.start else None,
        start_local_frame=master.start_local_frame if at == master.start else "",
    )


def _add_child(master: Segment, reason: ItoReason, at: datetime, uid=None) -> Segment:
    child = _new_child(master, reason, at, uid=uid)
    child.save()
    return child


@transaction.atomic
def report_mode(
    leg: Leg,
    mode: str,
    *,
    at: datetime | None = None,
    robot_stamp: datetime | None = None,
    gps: GpsPosition | None = None,
    local: LocalPosition | None = None,
    reason: str = ItoReason.UNASSIGNED,
    uid=None,
    start_uncertainty: float | None = None,
    suggested_reason: str | None = None,
    reason_uid=None,
) -> ModeReport:
    """The robot (or an importer) says which mode it is in now.

    Reporting the mode that is already open is not an error and changes
    nothing, so publishers that repeat their state are harmless.  ``uid`` is
    the new master's, ``reason_uid`` that of the reason a switch to ITO opens.
    """
    if mode not in MODES:
        modes = ", ".join(MODES)
        message = _("Mode must be one of %(modes)s, not '%(mode)s'.") % {
            "modes": modes,
            "mode": mode,
        }
        raise RuleViolation({"mode": [message]})
    if existing := stored_row(Segment, uid, leg_id=leg.pk):
        return ModeReport(existing, changed=False)
    # The shift comes along for the announcement (events.feed).
    leg = lock(leg, "shift")
    at = instant(at)
    require_open(leg, str(leg))
    current, reasons = _open_master_and_reasons(leg)
    if current is not None and current.segment_type_id == mode:
        return ModeReport(current, changed=False)
    ended = []
    if current is not None:
        require_not_before(
            current, at, _("The open %(mode)s segment") % {"mode": current.segment_type_id.upper()}
        )
        ended = _end(current, at, reasons)
    else:
        require_not_before(leg, at, str(leg))
    positions = _position_fields(gps, local)
    started = _start_master(
        leg,
        mode,
        at,
        robot_stamp,
        positions,
        reason,
        uid,
        start_uncertainty=start_uncertainty,
        reason_uid=reason_uid,
        suggested_reason=suggested_reason,
    )
    # The switch's history entries (rows ended and started) in one write.
    write_history(Segment, changed=ended, created=started)
    return ModeReport(announce_and_return(started[0]), changed=True)


@transaction.atomic
def new_manual_segment(
    leg: Leg,
    *,
    reason: str = ItoReason.UNASSIGNED,
    at: datetime | None = None,
    gps: GpsPosition | None = None,
    local: LocalPosition | None = None,
    uid=None,
) -> Segment:
    """An operator records a take-over: a new reason under the open ITO master,
    or, while AUTO runs (or nothing is open), a switch to ITO.  Returns the child.

    ``uid`` is the child's: a page that kept the take-over while offline sends it
    again until it hears an answer, and a uid already stored answers that row."""
    if existing := stored_row(Segment, uid, leg_id=leg.pk):
        return existing
    leg = lock(leg)
    at = instant(at)
    require_open(leg, str(leg))
    current = _open_master(leg)
    if current is not None and current.segment_type_id == SegmentType.ITO:
        require_not_before(current, at, _("The open ITO segment"))
        return announce_and_return(_add_child(current, _reason(reason), at, uid=uid))
    outcome = report_mode(
        leg, SegmentType.ITO, at=at, gps=gps, local=local, reason=reason, reason_uid=uid
    )
    return outcome.master.children.get()


@transaction.atomic
def add_ito_child(
    master: Segment, *, reason: str = ItoReason.UNASSIGNED, at: datetime | None = None
) -> Segment:
    master = _lock_with_leg(master)
    at = instant(at)
    if master.parent_id is not None:
        raise RuleViolation(_("Reasons are added to the ITO master segment, not to a reason."))
    if master.segment_type_id != SegmentType.ITO:
        raise RuleViolation(_("An AUTO segment has no take-over reasons."))
    require_open(master, _("This ITO segment"))
    require_not_before(master, at, _("This ITO segment"))
    return announce_and_return(_add_child(master, _reason(reason), at))


@transaction.atomic
def close_segment(segment: Segment, at: datetime | None = None) -> Segment:
    """Closing a child ends only that reason; closing a master ends its children too."""
    segment = _lock_with_leg(segment)
    at = instant(at)
    require_open(segment, _("This segment"))
    _close(segment, at)
    return announce_and_return(segment)


@transaction.atomic
def close_open_master(leg: Leg, at: datetime | None = None) -> Segment | None:
    """Used when logging stops: end whatever master is open, if any."""
    leg = lock(leg)
    at = instant(at)
    current, reasons = _open_master_and_reasons(leg)
    if current is not None:
        _close(announce_and_return(current), at, reasons)
    return current


@transaction.atomic
def annotate_segment(segment: Segment, **fields) -> Segment:
    """Set reason, obstacle, lighting or slope of an ITO reason (child segment).

    Empty strings clear the text fields; ``ito_reason`` takes a catalogue key.
    """
    segment = lock(segment)
    require_amendable(shifts__legs=segment.leg_id)
    if segment.parent_id is None:
        if segment.segment_type_id == SegmentType.AUTO:
            what = _("they cannot be set on an AUTO segment.")
        else:
            what = _("they cannot be set on a master.")
        raise RuleViolation(
            _("Reason, obstacle, lighting and slope describe an ITO take-over reason;") + " " + what
        )
    if "ito_reason" in fields and not isinstance(fields["ito_reason"], ItoReason):
        if fields["ito_reason"] is None:
            raise RuleViolation(
                {"ito_reason": [_("An ITO reason cannot be empty; use Unassigned.")]}
            )
        fields["ito_reason"] = _reason(fields["ito_reason"])
    apply_fields(segment, fields, Segment.ANNOTATION_FIELDS)
    segment.annotated = timezone.now()
    segment.save(update_fields=[*fields, "annotated"])
    return announce_and_return(segment)


@transaction.atomic
def annotate_open_take_over(leg: Leg, *, seen: int | None = None, **fields) -> Segment:
    """A quick reason: annotates the leg's open take-over (events.rules.open_take_overs),
    which the robot may have started a moment ago; an older take-over is annotated
    through :func:`annotate_segment`.

    ``seen`` is the take-over that was open when the operator tapped, sent by a page
    that kept the tap while offline: by the time it arrives another take-over may
    be open, and the reason belongs to the one the operator saw."""
    leg = lock(leg)
    if seen is not None:
        take_over = Segment.objects.children().filter(leg=leg, pk=seen).first()
        if take_over is None:
            raise NotFound(
                _(
                    "The take-over this reason was given to no longer exists; somebody "
                    "may have deleted it."
                )
            )
        return annotate_segment(take_over, **fields)
    take_over = rules.open_take_overs([leg.pk]).first()
    if take_over is None:
        raise RuleViolation(
            _(
                "No take-over is open in this leg; give an earlier take-over its reason "
                "in its segment's dialog."
            )
        )
    return annotate_segment(take_over, **fields)
