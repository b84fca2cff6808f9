"""What the GUI and the collectors share: the database is the only link.

A collector (``manage.py ftt_collect``) may run on the robot while the web
server runs elsewhere, so everything they exchange is a row here:

* :class:`Collector` is one collector's registration and heartbeat;
* :class:`CollectorCommand` is an order from the GUI and, later, its result.

What the collector stored is announced through the change feed
(:mod:`events.feed`), like every other write.
"""

from django.conf import settings
from django.db import models
from django.utils import timezone

from events.models import Leg, Vehicle


class Collector(models.Model):
    name = models.CharField(
        max_length=200, unique=True, help_text="host/node name; stable across restarts."
    )
    vehicle = models.ForeignKey(
        Vehicle, on_delete=models.SET_NULL, null=True, blank=True, related_name="collectors"
    )
    host = models.CharField(max_length=200, blank=True)
    pid = models.PositiveIntegerField(null=True, blank=True)
    started = models.DateTimeField(default=timezone.now)
    last_seen = models.DateTimeField(default=timezone.now, db_index=True)
    stopped = models.DateTimeField(
        null=True, blank=True, help_text="Set on a clean exit; a crash leaves it empty."
    )
    logging = models.BooleanField(default=False)
    leg = models.ForeignKey(
        Leg, on_delete=models.SET_NULL, null=True, blank=True, related_name="collectors"
    )
    state = models.CharField(
        max_length=500, blank=True, help_text="What the collector says about itself now."
    )
    pending = models.PositiveIntegerField(
        default=0, help_text="Records spooled on the robot, not yet in the database."
    )
    stored = models.PositiveBigIntegerField(
        default=0, help_text="Records written to the database since the collector started."
    )
    hearing = models.CharField(
        max_length=300,
        blank=True,
        help_text="Set while other nodes publish its topics and the collector hears nothing.",
    )
    disk = models.CharField(
        max_length=300,
        blank=True,
        help_text="Set while the robot's disk is (nearly) full: what the collector gives up.",
    )
    parameters = models.JSONField(default=dict, blank=True)
    topics = models.JSONField(default=list, blank=True)
    inputs = models.JSONField(default=dict, blank=True)

    class Meta:
        ordering = ["name"]

    def __str__(self):
        return self.name


class CollectorCommand(models.Model):
    class Kind(models.TextChoices):
        START_LOGGING = "start_logging", "start logging"
        STOP_LOGGING = "stop_logging", "stop logging"
        SET_PARAMETERS = "set_parameters", "set parameters"
        SAVE_PARAMETERS = "save_parameters", "save parameters"
        SNAPSHOT = "snapshot", "black-box snapshot now"

    collector = models.ForeignKey(Collector, on_delete=models.CASCADE, related_name="commands")
    kind = models.CharField(max_length=32, choices=Kind.choices)
    arguments = models.JSONField(default=dict, blank=True)
    issued = models.DateTimeField(default=timezone.now)
    issued_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
    )
    taken = models.DateTimeField(null=True, blank=True)
    done = models.DateTimeField(null=True, blank=True)
    success = models.BooleanField(null=True, blank=True)
    message = models.TextField(blank=True)
    result = models.JSONField(default=dict, blank=True)

    class Meta:
        ordering = ["id"]
        indexes = [models.Index(fields=["collector", "done"], name="command_todo")]

    def __str__(self):
        return f"{self.kind} → {self.collector}"
