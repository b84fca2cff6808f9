"""Load order of native libraries that exist twice in one process.

pyproj's and rasterio's wheels bundle their own PROJ and GDAL.  SQLite loads
mod_spatialite (and with it the system PROJ) with RTLD_GLOBAL; if that happens
first, the bundled copies bind their C++ globals to the system ones: pyproj
and the system PROJ then destroy the same objects at exit ("double free or
corruption", exit code 134), and importing rasterio (rio_tiler) crashes the
process.  Importing both before SpatiaLite's first connection keeps the bundled
copies self-contained.  PostgreSQL loads no such library, so there they stay
lazy loads of the code that uses them.
"""


def preload() -> None:
    import pyproj  # noqa: F401
    import rio_tiler.io  # noqa: F401
