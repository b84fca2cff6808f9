"""SpatiaLite backend that survives newer SQLite builds.

With SQLite >= 3.4x and SpatiaLite 5.0, Django's lazy ``InitSpatialMetaData``
runs too late and ``migrate`` fails inside the ISO metadata triggers (Django
ticket #32935).  Initialising the metadata tables up front avoids that.
"""

from django.contrib.gis.db.backends.spatialite import base


class DatabaseWrapper(base.DatabaseWrapper):
    def prepare_database(self):
        with self.cursor() as cursor:
            cursor.execute(
                "SELECT 1 FROM sqlite_master WHERE type='table' AND name='geometry_columns'"
            )
            if cursor.fetchone() is None:
                cursor.execute("SELECT InitSpatialMetaData(1)")
        super().prepare_database()
