from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _

from live import sessions, wakeup


class LiveConfig(AppConfig):
    name = "live"
    verbose_name = _("Live view")

    def ready(self):
        # Django's documented place for signal wiring: models load first.
        wakeup.connect()
        sessions.connect()
