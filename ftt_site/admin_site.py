"""The Django admin, branded and sorted the way a test administrator works:
what is configured before a test apart from what the field test recorded."""

from django.contrib import admin
from django.contrib.admin.apps import SimpleAdminConfig
from django.utils.translation import gettext_lazy as _

from common import roles

# Model names (object_name) per group; anything not named keeps Django's app grouping.
GROUPS = (
    (
        _("Configuration"),
        "configuration",
        (
            "Personnel",
            "Performer",
            "Vehicle",
            "RobotAccount",
            "PoseSource",
            "Weather",
            "ItoReason",
            "SegmentType",
        ),
    ),
    (
        _("Recorded data"),
        "recorded-data",
        (
            "TestEvent",
            "Shift",
            "Leg",
            "Segment",
            "Note",
            "Pose",
            "LocalPose",
            "MapImage",
            "Image",
        ),
    ),
)


# Libraries' own records (sign-in failures, background tasks, API tokens): only a
# superuser looks after them; to everyone else they are noise beside the logbook.
LIBRARY_APPS = {"axes", "authtoken", "django_tasks_db", "django_tasks"}


class FttAdminSite(admin.AdminSite):
    site_header = _("FTT administration")
    site_title = _("FTT administration")
    index_title = _("Set-up and records")

    def has_permission(self, request):
        # A robot account is never let in, even if someone ticked "staff status".
        return super().has_permission(request) and not roles.is_robot(request.user)

    def check(self, app_configs):
        # The admin modules load with the URLs (FttAdminConfig); the system
        # checks may run before the URLs are loaded and must see them all.
        admin.autodiscover()
        return super().check(app_configs)

    def get_app_list(self, request, app_label=None):
        apps = super().get_app_list(request, app_label)
        if app_label is not None:
            return apps
        grouped = []
        claimed = set()
        for name, label, members in GROUPS:
            models = [m for app in apps for m in app["models"] if m["object_name"] in members]
            models.sort(key=lambda m: members.index(m["object_name"]))
            claimed.update(id(m) for m in models)
            if models:
                grouped.append(
                    {
                        "name": name,
                        "app_label": label,
                        "app_url": "",
                        "has_module_perms": True,
                        "models": models,
                    }
                )
        for app in apps:
            if app["app_label"] in LIBRARY_APPS and not request.user.is_superuser:
                continue
            rest = [m for m in app["models"] if id(m) not in claimed]
            if rest:
                grouped.append({**app, "models": rest})
        return grouped


class FttAdminConfig(SimpleAdminConfig):
    """Admin modules are found when the URLs load (ftt_site/urls.py), not in
    every process at start: the collector and the job worker never show the
    admin, and the basemap admin alone brings in the raster libraries (seconds
    of the collector's start-up)."""

    default_site = "ftt_site.admin_site.FttAdminSite"
