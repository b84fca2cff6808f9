from django.apps import AppConfig
from django.conf import settings
from django.utils.translation import gettext_lazy as _

from basemaps.confinement import confine_gdal


class BasemapsConfig(AppConfig):
    name = "basemaps"
    verbose_name = _("Basemaps")

    def ready(self):
        confine_gdal()
        # rasterio's wheel brings its own GDAL and PROJ. Loaded after SpatiaLite's
        # mod_spatialite has bound the system's libraries, it crashes the process
        # (a segfault importing rio_tiler after the first SpatiaLite connection).
        # On the embedded database it is therefore loaded now, before any
        # connection; on PostgreSQL it stays a lazy load.
        if "spatialite" in settings.DATABASES["default"]["ENGINE"]:
            import rio_tiler.io  # noqa: F401
