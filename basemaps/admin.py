"""Basemap layers, managed by administrators; everyone with admin access may look."""

from django import forms
from django.contrib import admin
from django.core.exceptions import ValidationError
from django.utils.translation import gettext as _

from basemaps.models import BasemapLayer, EventBasemap
from basemaps.services import layers
from common import roles


class BasemapLayerForm(forms.ModelForm):
    class Meta:
        model = BasemapLayer
        fields = ["name", "key", "file", "url", "enabled", "attribution", "min_zoom", "max_zoom"]

    def clean(self):
        data = super().clean()
        upload = self.files.get("file")
        has_file = bool(upload) or bool(self.instance.file and data.get("file"))
        if has_file == bool(data.get("url")):
            raise ValidationError(_("Give either a file (GeoTIFF, MBTiles, PMTiles) or a URL."))
        if upload:
            try:
                layers.check_upload(self.instance, upload)
            except ValidationError as exc:
                self.add_error("file", exc)
                return data
            # Zooms and bounds come from the file, not from the form's defaults.
            data["min_zoom"], data["max_zoom"] = self.instance.min_zoom, self.instance.max_zoom
        elif data.get("url"):
            self.instance.kind = BasemapLayer.URL
            self.instance.west = self.instance.south = None
            self.instance.east = self.instance.north = None
        return data


class RoleAdmin(admin.ModelAdmin):
    def has_add_permission(self, request):
        return roles.may_write(request.user, self.model)

    def has_change_permission(self, request, obj=None):
        return roles.may_write(request.user, self.model)

    def has_delete_permission(self, request, obj=None):
        return roles.may_write(request.user, self.model)

    def has_view_permission(self, request, obj=None):
        return roles.has_role(request.user, roles.VIEWER)


@admin.register(BasemapLayer)
class BasemapLayerAdmin(RoleAdmin):
    form = BasemapLayerForm
    list_display = ["name", "key", "kind", "enabled", "min_zoom", "max_zoom", "attribution"]
    readonly_fields = ["kind", "west", "south", "east", "north", "tile_format"]
    prepopulated_fields = {"key": ["name"]}


@admin.register(EventBasemap)
class EventBasemapAdmin(RoleAdmin):
    list_display = ["test_event", "layer"]
