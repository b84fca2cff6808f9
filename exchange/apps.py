from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _


class ExchangeConfig(AppConfig):
    """Moving test data between installations; its one table is the queued archive imports."""

    name = "exchange"
    verbose_name = _("Data exchange")
