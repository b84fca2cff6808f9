"""Make the stdlib ``sqlite3`` module able to load SpatiaLite.

pyenv builds of CPython (the default ``python3`` on our machines) are compiled
without ``enable_load_extension``; Django's SpatiaLite backend needs it.  The
``pysqlite3-binary`` wheel bundles a SQLite that can, so we alias it in before
Django imports ``sqlite3``.  Interpreters that already support extensions
(Debian's ``/usr/bin/python3``) are left alone.
"""

import sqlite3
import sys


def install() -> None:
    if hasattr(sqlite3.Connection, "enable_load_extension"):
        return
    try:
        import pysqlite3
        import pysqlite3.dbapi2
    except ImportError:  # pragma: no cover - reported by Django as ImproperlyConfigured
        return
    sys.modules["sqlite3"] = pysqlite3
    sys.modules["sqlite3.dbapi2"] = pysqlite3.dbapi2
