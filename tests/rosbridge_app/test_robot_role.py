"""A robot's collector records a drive with the least-privilege PostGIS role
that ``ftt_robot_role`` grants, and cannot read accounts or tokens."""

import os
from datetime import UTC, datetime, timedelta

import pytest
from django.core.management import call_command
from django.db import DatabaseError, connection, transaction

from events.models import Segment
from rosbridge_app.collector import events as ev
from rosbridge_app.collector.event_writer import EventWriter
from rosbridge_app.collector.events import Event
from telemetry.models import Pose
from telemetry.storage.postgresql import COPY_FROM

pytestmark = [pytest.mark.postgis_only, pytest.mark.django_db]

AT = datetime(2026, 5, 4, 9, 0, tzinfo=UTC)


@pytest.fixture
def as_robot(db):
    role = f"ftt_robot_test_{os.getpid()}"
    call_command("ftt_robot_role", role, "--apply", stdout=open(os.devnull, "w"))  # noqa: SIM115
    with connection.cursor() as cursor:
        # A temporary staging table an earlier test made in this session belongs
        # to the test's own role; a robot's collector has its own session.
        cursor.execute("DISCARD TEMP")
        cursor.execute(f'SET ROLE "{role}"')
    yield role
    with connection.cursor() as cursor:
        cursor.execute("RESET ROLE")


def test_the_robot_role_records_a_drive_and_cannot_read_accounts(leg, as_robot):
    EventWriter(lambda: leg).apply(
        [
            Event(ev.START, AT),
            Event(ev.MODE, AT + timedelta(seconds=1), {"mode": "auto"}),
            Event(ev.GPS_FIX, AT + timedelta(seconds=2), {"lon": 7.1, "lat": 50.6}),
            Event(ev.GPS_FIX, AT + timedelta(seconds=3), {"lon": 7.1001, "lat": 50.6}),
        ]
    )
    master = Segment.objects.get(leg=leg, parent__isnull=True)
    assert master.segment_type_id == "auto"
    assert Pose.objects.filter(segment=master).count() == 2
    # A burst big enough to be copied through a temporary table (COPY_FROM).
    EventWriter(lambda: leg).apply(
        [
            Event(ev.GPS_FIX, AT + timedelta(seconds=4, milliseconds=i), {"lon": 7.1, "lat": 50.6})
            for i in range(COPY_FROM)
        ]
    )
    assert Pose.objects.filter(segment=master).count() == 2 + COPY_FROM
    for table in ("auth_user", "authtoken_token", "django_session"):
        with pytest.raises(DatabaseError, match="permission denied"), transaction.atomic():
            with connection.cursor() as cursor:
                cursor.execute(f"SELECT * FROM {table}")
