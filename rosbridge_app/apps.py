from django.apps import AppConfig


class RosbridgeAppConfig(AppConfig):
    name = "rosbridge_app"
    verbose_name = "Robot bridge"
