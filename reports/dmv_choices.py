"""The choice lists of the California DMV's disengagement form (OL 311R) and the
check that FTT's settings map its own values onto them (a system check,
``reports.checks``; the tables are ``reports.selectors.disengagements``)."""

from django.conf import settings

from events.models import Segment

INITIATED_BY = ("AV System", "Test Driver", "Remote Operator", "Passenger")
LOCATIONS = ("Interstate", "Freeway", "Highway", "Rural Road", "Street", "Parking Facility")


def check_dmv_settings() -> list[str]:
    """What is wrong in the DMV mapping settings, as sentences (none: all is well)."""
    problems = []
    known = {key for key, _label in Segment.INITIATORS}
    initiators = settings.FTT_DMV_INITIATORS
    for key in sorted(known - set(initiators)):
        problems.append(f"FTT_DMV_INITIATORS names no DMV choice for the initiator {key!r}.")
    for key, word in initiators.items():
        if key not in known:
            problems.append(f"FTT_DMV_INITIATORS: {key!r} is not an initiator of FTT.")
        elif word not in INITIATED_BY:
            problems.append(
                f"FTT_DMV_INITIATORS: {word!r} is not one of {', '.join(INITIATED_BY)}."
            )
    locations = [*settings.FTT_DMV_LOCATIONS.values(), settings.FTT_DMV_LOCATION_DEFAULT]
    for word in locations:
        if word not in LOCATIONS:
            problems.append(
                f"FTT_DMV_LOCATIONS / FTT_DMV_LOCATION_DEFAULT: {word!r} is not one of "
                f"{', '.join(LOCATIONS)}."
            )
    return problems
