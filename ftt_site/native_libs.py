"""Load order of native libraries that exist twice in one process.

pyproj's wheel bundles its own PROJ.  SQLite loads mod_spatialite (and with
it the system PROJ) with RTLD_GLOBAL; if that happens first, the bundled PROJ
binds its C++ globals to the system copy and both libraries destroy the same
objects at exit ("double free or corruption", exit code 134).  Importing
pyproj before any database connection keeps the bundled copy self-contained.
"""


def preload() -> None:
    import pyproj  # noqa: F401
