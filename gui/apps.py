from django.apps import AppConfig
from django.utils.translation import gettext_lazy as _


class GuiConfig(AppConfig):
    """The operator's web pages and the JSON reads only they need."""

    name = "gui"
    verbose_name = _("Web GUI")
