"""The change feed: one row per change a browser may want to redraw.

Services add a row in the same transaction as the change it describes
(:mod:`events.feed`), so the feed shows a change exactly when it is committed
and a rolled-back write announces nothing.  The live link
(:mod:`live.consumers`) tails it.
"""

from django.db import models
from django.utils import timezone
from django.utils.translation import gettext_lazy as _

from events.models.hierarchy import Leg


class Announcement(models.Model):
    """One thing a browser may want to redraw; ids only grow, so a reader keeps
    the last id it saw and asks for everything after it."""

    class Kind(models.TextChoices):
        COLLECTOR = "collector", _("collector status")
        LOG = "log", _("test event, shift or leg")
        DELETED = "deleted", _("row deleted")
        NOTE = "note", _("note")
        SEGMENT = "segment", _("segment opened or closed")
        POSES = "poses", _("GPS poses")
        LOCAL_POSES = "local_poses", _("local poses")
        IMAGE = "image", _("image")
        MAP = "map", _("map")
        COMMAND = "command", _("command result")

    kind = models.CharField(max_length=16, choices=Kind.choices, verbose_name=_("kind"))
    created = models.DateTimeField(default=timezone.now, db_index=True, verbose_name=_("created"))
    # A plain id: the feed sits below the collector link and must not know it.
    collector_id = models.BigIntegerField(null=True, blank=True, verbose_name=_("collector id"))
    leg = models.ForeignKey(
        Leg,
        on_delete=models.CASCADE,
        null=True,
        blank=True,
        related_name="+",
        verbose_name=_("leg"),
    )
    payload = models.JSONField(default=dict, blank=True, verbose_name=_("payload"))

    class Meta:
        verbose_name = _("announcement")
        verbose_name_plural = _("announcements")
        # The table keeps the name it had when the feed lived in rosbridge_app.
        db_table = "rosbridge_app_announcement"
        ordering = ["id"]

    def __str__(self):
        return f"#{self.pk} {self.kind}"
