"""Robot-recorded data: browsable, never editable by hand."""

from django.contrib import admin
from django.utils.html import format_html
from django.utils.translation import gettext_lazy as _
from simple_history.admin import SimpleHistoryAdmin

from events.admin.shared import ServiceDeleteMixin, admin_link
from telemetry.models import Image, LocalPose, MapImage, Pose


class RecordedDataAdmin(admin.ModelAdmin):
    list_per_page = 200

    def has_add_permission(self, request):
        return False

    def has_change_permission(self, request, obj=None):
        return False

    def get_readonly_fields(self, request, obj=None):
        return [f.name for f in self.model._meta.fields]

    @admin.display(description=_("segment"))
    def segment_link(self, obj):
        return admin_link(obj.segment)


@admin.register(Pose)
class PoseAdmin(ServiceDeleteMixin, RecordedDataAdmin):
    list_display = ["id", "segment_link", "longitude", "latitude", "fix_status", "robot_stamp"]
    list_filter = ["fix_status", "pose_source"]
    list_select_related = ["segment__segment_type"]

    @admin.display(description=_("longitude"))
    def longitude(self, obj):
        return f"{obj.point.x:.7f}"

    @admin.display(description=_("latitude"))
    def latitude(self, obj):
        return f"{obj.point.y:.7f}"


@admin.register(LocalPose)
class LocalPoseAdmin(ServiceDeleteMixin, RecordedDataAdmin):
    list_display = ["id", "segment_link", "frame", "x", "y", "yaw", "robot_stamp"]
    list_filter = ["frame"]
    list_select_related = ["segment__segment_type"]


def thumbnail(obj):
    if not obj.image:
        return "—"
    return format_html('<img src="{}" style="max-height:6em">', obj.image.url)


@admin.register(MapImage)
class MapImageAdmin(ServiceDeleteMixin, RecordedDataAdmin):
    list_display = ["__str__", "shift", "frame", "resolution", "received", thumbnail]
    list_select_related = ["shift"]


@admin.register(Image)
class ImageAdmin(ServiceDeleteMixin, RecordedDataAdmin, SimpleHistoryAdmin):
    list_display = ["__str__", "segment_link", "received", thumbnail]
    list_select_related = ["segment__segment_type"]
