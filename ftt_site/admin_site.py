"""The Django admin, branded and sorted the way a test administrator works:
what is configured before a test apart from what the field test recorded."""

from django.contrib import admin
from django.contrib.admin.apps import AdminConfig

from common import roles

# Model names (object_name) per group; anything not named keeps Django's app grouping.
GROUPS = (
    (
        "Configuration",
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
        "Recorded data",
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


class FttAdminSite(admin.AdminSite):
    site_header = "FTT administration"
    site_title = "FTT administration"
    index_title = "Set-up and records"

    def has_permission(self, request):
        # A robot account is never let in, even if someone ticked "staff status".
        return super().has_permission(request) and not roles.is_robot(request.user)

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
            rest = [m for m in app["models"] if id(m) not in claimed]
            if rest:
                grouped.append({**app, "models": rest})
        return grouped


class FttAdminConfig(AdminConfig):
    default_site = "ftt_site.admin_site.FttAdminSite"
