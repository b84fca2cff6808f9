from django.apps import AppConfig


class ExchangeConfig(AppConfig):
    """Moving test data between installations; its one table is the queued archive imports."""

    name = "exchange"
    verbose_name = "Data exchange"
