"""Robot accounts: logins (with a token) bound to the vehicles they log for."""

from django.conf import settings
from django.db import models
from django.utils.translation import gettext_lazy as _

from events.models.configuration import Vehicle


class RobotAccount(models.Model):
    """Binds a login in the ``robot`` group to its vehicles.

    Its token reports modes and writes telemetry only into legs of these
    vehicles (``events.rules.check_robot_target``); bound to none, it writes nothing.
    """

    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        on_delete=models.CASCADE,
        related_name="robot_account",
        help_text=_("The robot's login; put it in the robot group and give it a token."),
        verbose_name=_("user"),
    )
    vehicles = models.ManyToManyField(
        Vehicle,
        blank=True,
        related_name="robot_accounts",
        help_text=_("Vehicles whose legs this robot writes into; no others."),
        verbose_name=_("vehicles"),
    )

    class Meta:
        verbose_name = _("robot account")
        verbose_name_plural = _("robot accounts")
        ordering = ["user__username"]

    def __str__(self):
        return self.user.get_username()
