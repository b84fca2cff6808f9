"""Admin pages of the configuration: people, performers, vehicles, pose sources
and the catalogues (weather, take-over reasons, segment types)."""

from django.contrib import admin
from django.utils.html import format_html
from django.utils.translation import gettext_lazy as _

from common import roles
from events.admin.shared import HistoryAdmin, ServiceDeleteMixin
from events.models import (
    ItoReason,
    Performer,
    Personnel,
    PoseSource,
    RobotAccount,
    SegmentType,
    Vehicle,
    Weather,
)
from events.services import configuration


@admin.register(Personnel)
class PersonnelAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["name", "institution", "user"]
    search_fields = ["name", "institution", "user__username"]
    list_filter = ["institution"]
    autocomplete_fields = ["user"]


@admin.register(Performer)
class PerformerAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    list_display = ["institution"]
    search_fields = ["institution"]


class RobotBindingInline(admin.TabularInline):
    """On a vehicle's page: the robot accounts whose tokens log into its legs."""

    model = RobotAccount.vehicles.through
    extra = 0
    autocomplete_fields = ["robotaccount"]
    verbose_name = _("robot account")
    verbose_name_plural = _(
        "robot accounts logging for this vehicle (their tokens write here only)"
    )


@admin.register(Vehicle)
class VehicleAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["key", "short_description", "institution"]
    search_fields = ["key", "short_description", "long_description", "institution"]
    list_filter = ["institution"]
    inlines = [RobotBindingInline]


@admin.register(PoseSource)
class PoseSourceAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    list_display = ["key", "short_description"]
    search_fields = ["key", "short_description", "long_description"]


# --- catalogues -------------------------------------------------------------------------------


class CatalogueAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    """Everyone with admin access may look; only administrators change."""

    search_fields = ["key", "short_description", "long_description"]
    # Refuses the keys the logging rules name (unassigned, ito, auto, unknown).
    delete_service = staticmethod(configuration.delete_configuration)

    def _may_write(self, request):
        return roles.may_write(request.user, self.model)

    def has_add_permission(self, request):
        return self._may_write(request)

    def has_change_permission(self, request, obj=None):
        return self._may_write(request)

    def has_delete_permission(self, request, obj=None):
        if obj is not None and configuration.is_used_by_rules(obj):
            return False
        return self._may_write(request)

    def has_view_permission(self, request, obj=None):
        return roles.has_role(request.user, roles.VIEWER)

    def get_readonly_fields(self, request, obj=None):
        return ["key"] if obj is not None else []


def colour_swatch(obj):
    return format_html(
        '<span style="display:inline-block;width:1.5em;height:1em;background:rgb({})"></span> {}',
        obj.color,
        obj.color,
    )


colour_swatch.short_description = _("colour")


@admin.register(Weather)
class WeatherAdmin(CatalogueAdmin):
    list_display = ["key", "short_description", "long_description"]


@admin.register(ItoReason)
class ItoReasonAdmin(CatalogueAdmin, HistoryAdmin):
    list_display = ["key", "short_description", colour_swatch, "counts_as_intervention", "quick"]
    list_filter = ["counts_as_intervention", "quick"]


@admin.register(SegmentType)
class SegmentTypeAdmin(CatalogueAdmin):
    list_display = ["key", "short_description", colour_swatch]

    def has_add_permission(self, request):
        # The state machine knows ITO, AUTO and UNKNOWN only; another type could never be logged.
        return False
