from django.apps import AppConfig


class GuiConfig(AppConfig):
    """The operator's web pages and the JSON reads only they need."""

    name = "gui"
    verbose_name = "Web GUI"
