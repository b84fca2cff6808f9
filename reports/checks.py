"""System checks of the report settings an administrator sets in the environment."""

from django.core.checks import Error, register

from reports.dmv_choices import check_dmv_settings


@register()
def dmv_choices_known(app_configs, **kwargs):
    return [Error(problem, id="ftt.E010") for problem in check_dmv_settings()]
