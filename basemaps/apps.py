from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _

from basemaps.confinement import confine_gdal


class BasemapsConfig(AppConfig):
    name = "basemaps"
    verbose_name = _("Basemaps")

    def ready(self):
        # rasterio is loaded by the code that reads rasters; on SpatiaLite before
        # the first connection (ftt_site.db_spatialite.native_libs), as its GDAL requires.
        confine_gdal()
