"""SpatiaLite backend that survives newer SQLite builds and keeps its busy timeout.

With SQLite >= 3.4x and SpatiaLite 5.0, Django's lazy ``InitSpatialMetaData``
runs too late and ``migrate`` fails inside the ISO metadata triggers (Django
ticket #32935).  Initialising the metadata tables up front avoids that.

Loading ``mod_spatialite`` sets the connection's busy timeout to SpatiaLite's
own 5 s, replacing the one Django gave ``sqlite3.connect`` (``OPTIONS["timeout"]``),
so a writer queued for the write lock would give up sooner than the settings
promise; the timeout is set again once the extension is in.

The wheels' own PROJ and GDAL are loaded before the first connection loads
``mod_spatialite`` (``ftt_site.db_spatialite.native_libs``).
"""

from django.contrib.gis.db.backends.spatialite import base

from ftt_site.db_spatialite import native_libs

# What sqlite3.connect uses when OPTIONS has no "timeout".
SQLITE_DEFAULT_TIMEOUT = 5.0


class DatabaseWrapper(base.DatabaseWrapper):
    def get_new_connection(self, conn_params):
        native_libs.preload()
        conn = super().get_new_connection(conn_params)
        timeout = conn_params.get("timeout", SQLITE_DEFAULT_TIMEOUT)
        conn.execute(f"PRAGMA busy_timeout = {round(timeout * 1000)}")
        return conn

    def prepare_database(self):
        with self.cursor() as cursor:
            cursor.execute(
                "SELECT 1 FROM sqlite_master WHERE type='table' AND name='geometry_columns'"
            )
            if cursor.fetchone() is None:
                cursor.execute("SELECT InitSpatialMetaData(1)")
        super().prepare_database()
