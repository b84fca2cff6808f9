from django.urls import path, register_converter

from basemaps import views


class TileFormat:
    regex = "png|webp"

    def to_python(self, value):
        return value

    def to_url(self, value):
        return value


register_converter(TileFormat, "tilefmt")

urlpatterns = [
    path("<slug:key>/<int:z>/<int:x>/<int:y>.<tilefmt:fmt>", views.tile, name="basemap-tile"),
]
