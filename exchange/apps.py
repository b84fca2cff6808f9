from django.apps import AppConfig


class ExchangeConfig(AppConfig):
    """Moving test data between installations; it has no tables of its own."""

    name = "exchange"
    verbose_name = "Data exchange"
