from django.conf import settings
from django.utils.translation import get_language

from events import rules
from events.models import Leg, Performer, Personnel, PoseSource, Segment, Vehicle


def open_leg_for_vehicle(vehicle) -> Leg | None:
    """The leg a robot logs into: the open leg of its vehicle's open shift."""
    return (
        Leg.objects.select_related("shift", "shift__test_event")
        .filter(shift__vehicle=vehicle, shift__end__isnull=True, end__isnull=True)
        .first()
    )


def open_master(leg: Leg) -> Segment | None:
    return rules.open_masters_of_leg(leg.pk).first()


# The people of a shift; a new shift names the user for each of them.
SHIFT_PEOPLE = ("test_administrator", "test_director", "robot_operator", "safety_officer")


def new_entry_values(level: str, person: Personnel | None) -> dict:
    """What a new test event, shift or leg starts with in its dialog: only
    unambiguous choices (the user's own person; a vehicle, performer or pose
    source when exactly one exists, or the performer of the user's institution)."""
    values = {}
    if level == "event":
        # The report's language: the one this person reads the page in.
        language = (get_language() or "")[:2]
        codes = [code for code, _name in settings.LANGUAGES]
        values["language"] = language if language in codes else settings.LANGUAGE_CODE[:2]
    elif level == "shift":
        vehicles = list(Vehicle.objects.values_list("pk", flat=True)[:2])
        if len(vehicles) == 1:
            values["vehicle"] = vehicles[0]
        performers = list(Performer.objects.values_list("pk", flat=True)[:2])
        if len(performers) == 1:
            values["performer"] = performers[0]
        elif person is not None:
            own = Performer.objects.filter(institution=person.institution).first()
            if own is not None and person.institution:
                values["performer"] = own.pk
        if person is not None:
            values.update(dict.fromkeys(SHIFT_PEOPLE, person.pk))
    elif level == "leg":
        sources = list(PoseSource.objects.values_list("pk", flat=True)[:2])
        if len(sources) == 1:
            values["default_pose_source"] = sources[0]
    return values


def missing_for_new(level: str) -> str:
    """Why a new entry of this level cannot be made yet ("" when it can)."""
    if level == "shift" and not Vehicle.objects.exists():
        return "Configure a vehicle first (Configuration → Vehicles)."
    return ""
