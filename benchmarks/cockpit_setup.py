"""The operator, vehicle, test event and shift the cockpit benchmarks start
from: the head of a snippet for ``Server.python``, formatted with the
operator's ``password`` (braces that stay are doubled)."""

OPERATOR_AND_SHIFT = """
import json
from django.contrib.auth.models import Group, User
from events.models import PoseSource, Vehicle
from events.services import logs, segments
from telemetry.services import pose_writes
u = User.objects.create_user("otto", password={password!r})
u.groups.add(Group.objects.get(name="operator"))
PoseSource.objects.get_or_create(key="gps", defaults={{"short_description": "GPS"}})
v = Vehicle.objects.create(key="bench", short_description="Bench rover")
e = logs.create_test_event(location="Bench field", time_zone="Europe/Berlin")
s = logs.create_shift(test_event=e, vehicle=v)
"""
