from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _


class RosbridgeAppConfig(AppConfig):
    name = "rosbridge_app"
    verbose_name = _("Robot bridge")

    def ready(self):
        # Django's documented place for signal wiring: models load first.
        from rosbridge_app.services import collectors  # noqa: PLC0415

        collectors.connect()
