"""Robot accounts: logins (with a token) bound to the vehicles they log for."""

from django.conf import settings
from django.db import models

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
        help_text="The robot's login; put it in the robot group and give it a token.",
    )
    vehicles = models.ManyToManyField(
        Vehicle,
        blank=True,
        related_name="robot_accounts",
        help_text="Vehicles whose legs this robot writes into; no others.",
    )

    class Meta:
        ordering = ["user__username"]

    def __str__(self):
        return self.user.get_username()
