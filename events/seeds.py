"""The seeded catalogues and role groups.

Used by migration events.0002 and again by tests that flush the database
(transactional tests), so both get exactly the same rows.  Every function is
idempotent and takes an app registry (the migration's historical one or the
live ``django.apps.apps``).
"""

from django.contrib.auth.management import create_permissions
from django.utils.translation import gettext, gettext_noop

from common import roles

WEATHER = [
    (
        "sunny",
        gettext_noop("sunny"),
        gettext_noop("Mainly sunny, less than 30 percent of the sky is covered by clouds."),
        "sun",
    ),
    (
        "cloudy",
        gettext_noop("cloudy"),
        gettext_noop("Mainly cloudy, between 30 and 95 percent of the sky is covered by clouds."),
        "cloudy",
    ),
    (
        "overcast",
        gettext_noop("overcast"),
        gettext_noop("More than 95 percent of the sky is covered by clouds."),
        "overcast",
    ),
    (
        "foggy",
        gettext_noop("foggy"),
        gettext_noop("Reduced visibility due to fog to less than one kilometer."),
        "fog",
    ),
    ("rainy", gettext_noop("rainy"), "", "rain"),
    ("snowy", gettext_noop("snowy"), "", "snow"),
]

# key, short, long, colour, counts as an intervention
ITO_REASONS = [
    (
        "safety",
        gettext_noop("Safety"),
        gettext_noop("Safety stop, initiated by an inhabitant of the vehicle."),
        "255,0,0",
        True,
    ),
    (
        "maintenance",
        gettext_noop("Maintenance"),
        gettext_noop("Maintenance stop, a stop initiated by the performer to fix code."),
        "255,240,0",
        True,
    ),
    (
        "planner",
        gettext_noop("Planner"),
        gettext_noop("Planner stop, a stop caused by a timeout or error of the planner."),
        "255,120,0",
        True,
    ),
    (
        "apparatus",
        gettext_noop("Apparatus"),
        gettext_noop(
            "Apparatus stop, a stop that is initiated by the test admin to fix the test apparatus."
        ),
        "70,0,255",
        True,
    ),
    (
        "non_stop",
        gettext_noop("Non-Stop"),
        gettext_noop("Non-Stop, indicates that no stop was performed. Ignore this ITO."),
        "10,120,10",
        False,
    ),
    (
        "stereo",
        gettext_noop("Stereo test"),
        gettext_noop(
            "Stereo test stop, a stop initiated to perform a test of the stereo accuracy."
        ),
        "0,170,255",
        True,
    ),
    (
        "goal",
        gettext_noop("Goal reached"),
        gettext_noop("Goal reached, a stop because the vehicle reached an (intermediate) goal."),
        "0,0,139",
        False,
    ),
    (
        "end_shift",
        gettext_noop("End of shift"),
        gettext_noop(
            "End of shift indicates the stop was caused because the time for the shift was up."
        ),
        "0,0,220",
        False,
    ),
    (
        "manual_transit",
        gettext_noop("Manual transit"),
        gettext_noop(
            "Manual transit indicates that the vehicle was stopped to drive it manually "
            "through a dangerous area."
        ),
        "100,100,100",
        True,
    ),
    ("other", gettext_noop("Other"), gettext_noop("Other reasons."), "180,180,180", True),
    ("unassigned", gettext_noop("Unassigned"), gettext_noop("Unassigned."), "80,80,80", True),
    (
        "unexpected",
        gettext_noop("Unexpected"),
        gettext_noop("Unexpected, non safety-critical behavior."),
        "200,200,0",
        True,
    ),
]

# The cockpit's one-tap reasons: the original's four most used take-overs.
QUICK_REASONS = ["unexpected", "planner", "safety", "manual_transit"]

SEGMENT_TYPES = [
    ("ito", "ITO", gettext_noop("ITO - inhabited take over (manual mode)."), "255,0,0"),
    ("auto", "AUTO", gettext_noop("Autonomous."), "0,255,0"),
    (
        "unknown",
        gettext_noop("Unknown"),
        gettext_noop("Mode not known: logged before the robot said its mode."),
        "150,150,150",
    ),
]

# The seeded texts of each catalogue entry: (model name, key) -> (short, long).
SEEDED_TEXTS = {
    **{("weather", key): (short, long) for key, short, long, _ in WEATHER},
    **{("itoreason", key): (short, long) for key, short, long, *_ in ITO_REASONS},
    **{("segmenttype", key): (short, long) for key, short, long, _ in SEGMENT_TYPES},
}


def catalogue_text(model_name: str, key: str, text: str) -> str:
    """A catalogue entry's text as its reader sees it: the seeded words in the
    reader's language; an entry an administrator added or rewrote, as written."""
    return gettext(text) if text and text in SEEDED_TEXTS.get((model_name, key), ()) else text


CONFIGURATION = ["personnel", "performer", "vehicle", "posesource"]
CATALOGUES = ["weather", "itoreason", "segmenttype"]


def seed_catalogues(apps) -> None:
    Weather = apps.get_model("events", "Weather")
    ItoReason = apps.get_model("events", "ItoReason")
    SegmentType = apps.get_model("events", "SegmentType")
    for key, short, long, icon in WEATHER:
        Weather.objects.update_or_create(
            key=key,
            defaults={
                "short_description": short,
                "long_description": long,
                "icon": icon,
            },
        )
    for key, short, long, color, counts in ITO_REASONS:
        ItoReason.objects.update_or_create(
            key=key,
            defaults={
                "short_description": short,
                "long_description": long,
                "color": color,
                "counts_as_intervention": counts,
            },
        )
    for key, short, long, color in SEGMENT_TYPES:
        SegmentType.objects.update_or_create(
            key=key,
            defaults={
                "short_description": short,
                "long_description": long,
                "color": color,
            },
        )


def create_roles(apps) -> None:
    # Permissions are normally made after all migrations; the groups need them now.
    for app_config in apps.get_app_configs():
        original = getattr(app_config, "models_module", None)
        app_config.models_module = original or True
        create_permissions(app_config, apps=apps, verbosity=0)
        app_config.models_module = original

    Group = apps.get_model("auth", "Group")
    Permission = apps.get_model("auth", "Permission")
    ftt = Permission.objects.filter(content_type__app_label__in=roles.ROLE_APPS)
    operated = Permission.objects.none()
    for label in roles.written_by(roles.OPERATOR):
        app_label, model = label.split(".")
        operated |= Permission.objects.filter(
            content_type__app_label=app_label,
            codename__in=[f"{action}_{model}" for action in ("add", "change", "delete")],
        )
    robot_may = Permission.objects.none()
    for label in roles.ROBOT_WRITES:
        app_label, model = label.split(".")
        robot_may |= Permission.objects.filter(
            content_type__app_label=app_label, codename=f"add_{model}"
        )
    viewed = ftt.filter(codename__startswith="view_")
    for name, wanted in (
        (roles.VIEWER, viewed),
        (roles.OPERATOR, viewed | operated),
        (roles.ADMINISTRATOR, ftt | Permission.objects.filter(content_type__app_label="auth")),
        (roles.ROBOT, robot_may),
    ):
        group, _ = Group.objects.get_or_create(name=name)
        # Added, never taken away: a right an administrator gave a group in
        # Django admin (finalising, for a test director's group) stays.
        group.permissions.add(*wanted)


def mark_quick_reasons(apps) -> None:
    ItoReason = apps.get_model("events", "ItoReason")
    ItoReason.objects.filter(key__in=QUICK_REASONS).update(quick=True)
