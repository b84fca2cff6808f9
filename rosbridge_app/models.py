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
from django.utils.translation import gettext_lazy as _

from events.models import Leg, Vehicle


class Collector(models.Model):
    name = models.CharField(
        max_length=200,
        unique=True,
        help_text=_("host/node name; stable across restarts."),
        verbose_name=_("name"),
    )
    vehicle = models.ForeignKey(
        Vehicle,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="collectors",
        verbose_name=_("vehicle"),
    )
    host = models.CharField(max_length=200, blank=True, verbose_name=_("host"))
    pid = models.PositiveIntegerField(null=True, blank=True, verbose_name=_("pid"))
    started = models.DateTimeField(default=timezone.now, verbose_name=_("started"))
    last_seen = models.DateTimeField(
        default=timezone.now, db_index=True, verbose_name=_("last seen")
    )
    stopped = models.DateTimeField(
        null=True,
        blank=True,
        help_text=_("Set on a clean exit; a crash leaves it empty."),
        verbose_name=_("stopped"),
    )
    logging = models.BooleanField(default=False, verbose_name=_("logging"))
    leg = models.ForeignKey(
        Leg,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="collectors",
        verbose_name=_("leg"),
    )
    state = models.CharField(
        max_length=500,
        blank=True,
        help_text=_("What the collector says about itself now."),
        verbose_name=_("state"),
    )
    pending = models.PositiveIntegerField(
        default=0,
        help_text=_("Records spooled on the robot, not yet in the database."),
        verbose_name=_("pending"),
    )
    stored = models.PositiveBigIntegerField(
        default=0,
        help_text=_("Records written to the database since the collector started."),
        verbose_name=_("stored"),
    )
    hearing = models.CharField(
        max_length=300,
        blank=True,
        help_text=_("Set while other nodes publish its topics and the collector hears nothing."),
        verbose_name=_("hearing"),
    )
    disk = models.CharField(
        max_length=300,
        blank=True,
        verbose_name=_("disk"),
        help_text=_("Set while the robot's disk is (nearly) full: what the collector gives up."),
    )
    parameters = models.JSONField(default=dict, blank=True, verbose_name=_("parameters"))
    topics = models.JSONField(default=list, blank=True, verbose_name=_("topics"))
    inputs = models.JSONField(default=dict, blank=True, verbose_name=_("inputs"))

    class Meta:
        verbose_name = _("collector")
        verbose_name_plural = _("collectors")
        ordering = ["name"]

    def __str__(self):
        return self.name


class CollectorCommand(models.Model):
    class Kind(models.TextChoices):
        START_LOGGING = "start_logging", _("start logging")
        STOP_LOGGING = "stop_logging", _("stop logging")
        SET_PARAMETERS = "set_parameters", _("set parameters")
        SAVE_PARAMETERS = "save_parameters", _("save parameters")
        SNAPSHOT = "snapshot", _("black-box snapshot now")

    collector = models.ForeignKey(
        Collector, on_delete=models.CASCADE, related_name="commands", verbose_name=_("collector")
    )
    kind = models.CharField(max_length=32, choices=Kind.choices, verbose_name=_("kind"))
    arguments = models.JSONField(default=dict, blank=True, verbose_name=_("arguments"))
    issued = models.DateTimeField(default=timezone.now, verbose_name=_("issued"))
    issued_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        on_delete=models.SET_NULL,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("issued by"),
    )
    taken = models.DateTimeField(null=True, blank=True, verbose_name=_("taken"))
    done = models.DateTimeField(null=True, blank=True, verbose_name=_("done"))
    success = models.BooleanField(null=True, blank=True, verbose_name=_("success"))
    message = models.TextField(blank=True, verbose_name=_("message"))
    result = models.JSONField(default=dict, blank=True, verbose_name=_("result"))

    class Meta:
        verbose_name = _("collector command")
        verbose_name_plural = _("collector commands")
        ordering = ["id"]
        indexes = [models.Index(fields=["collector", "done"], name="command_todo")]

    def __str__(self):
        return f"{self.kind} → {self.collector}"
