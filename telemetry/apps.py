from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _


class TelemetryConfig(AppConfig):
    name = "telemetry"
    verbose_name = _("Robot data")

    def ready(self):
        # Django's documented place for signal wiring: models load first.
        from telemetry.services import pose_writes  # noqa: PLC0415

        pose_writes.connect()
