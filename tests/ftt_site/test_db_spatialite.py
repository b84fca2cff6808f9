"""The embedded database backend: writers queue for the lock as long as the settings say."""

import pytest
from django.db import connection

# On SpatiaLite too: the SpatiaLite backend itself.
pytestmark = [
    pytest.mark.spatialite,
    pytest.mark.django_db,
    pytest.mark.skipif(connection.vendor != "sqlite", reason="SpatiaLite backend"),
]


def test_a_new_connection_waits_for_the_write_lock_as_long_as_configured():
    # Loading mod_spatialite used to cut the wait to 5 s: under many clients a
    # writer then failed with "database is locked" while others still queued.
    fresh = connection.get_new_connection(connection.get_connection_params())
    try:
        waits_ms = fresh.execute("PRAGMA busy_timeout").fetchone()[0]
    finally:
        fresh.close()
    assert waits_ms == 1000 * connection.settings_dict["OPTIONS"]["timeout"]
    assert waits_ms > 5000
